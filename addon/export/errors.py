"""The export's two ways of failing: a scene that cannot be rendered (the message says why) and
a cancel during the export."""


class ExportError(Exception):
    """The scene cannot be rendered; the message says why, for the user."""


class ExportCancelled(Exception):
    """The user cancelled (test_break) while the scene was being exported."""
