"""What the engine reports during a test's renders (RenderEngine.report), for the `said`
fixtures of tests/addon and tests/parity."""


def recorded_reports(monkeypatch):
    """A list that collects the texts DACRT reports from now on (monkeypatch undoes it)."""
    from addon.engine import DACRTRenderEngine
    texts = []
    real = DACRTRenderEngine._report_messages

    def record(self, messages):
        texts.extend(text for _, text in messages)
        return real(self, messages)
    monkeypatch.setattr(DACRTRenderEngine, '_report_messages', record)
    return texts
