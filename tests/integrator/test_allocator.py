"""The render-time allocator policy (addon/allocator.py): active on glibc, harmless around
errors, and a render inside it gives the same image as one outside it."""
import contextlib
import platform

import numpy as np
import pytest

import addon.integrator as integrator_module
from addon import allocator

from . import scenes


def test_policy_is_active_on_glibc():
    if platform.system() == 'Linux' and platform.libc_ver()[0] == 'glibc':
        assert allocator._LIBC is not None
    else:
        assert allocator._LIBC is None


def test_policy_restores_after_an_error():
    with pytest.raises(RuntimeError):
        with allocator.render_heap():
            raise RuntimeError("boom")
    with allocator.render_heap():          # usable again afterwards
        big = np.ones(8 << 20, np.float32)
        assert big.sum() == 8 << 20


def test_image_does_not_depend_on_the_policy(monkeypatch):
    sd = scenes.cornell_box(width=24, height=18, samples=4, max_bounces=2, area_light=True)
    held = scenes.render(sd).film.combined()
    monkeypatch.setattr(integrator_module, 'render_heap', contextlib.nullcontext)
    plain = scenes.render(sd).film.combined()
    np.testing.assert_array_equal(held, plain)


def test_nested_and_interleaved_uses_restore_once():
    outer, inner = allocator.render_heap(), allocator.render_heap()
    outer.__enter__()
    inner.__enter__()
    outer.__exit__(None, None, None)          # the outer one may end first (generators)
    assert allocator._depth == 1
    inner.__exit__(None, None, None)
    assert allocator._depth == 0
