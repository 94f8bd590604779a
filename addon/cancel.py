"""Cancellation of a render (Esc, RenderEngine.test_break) as the integrator raises it: during
set-up (the render reports it and stops) or inside a pass (the pass's samples are dropped)."""
from contextlib import contextmanager

import dacrt


class SetupCancelled(Exception):
    """The render was cancelled (check_break) while the integrator was being set up."""


class PassCancelled(Exception):
    """Cancel (check_break) polled inside a pass: the pass's samples are not added."""


@contextmanager
def tracer_cancel():
    """Inside a pass: the tracer stopped by its cancel check (dacrt.Cancelled) is a cancelled
    pass, as a poll between bounces is."""
    try:
        yield
    except dacrt.Cancelled:
        raise PassCancelled() from None
