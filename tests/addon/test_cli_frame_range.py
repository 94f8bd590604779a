"""`python -m addon.cli render --frame N` outside Blender's frame range (-1048574 .. 1048574)
is refused with a message naming the range, before anything is opened or rendered: frame_set
had clamped a frame past it without a word (2000000 rendered and wrote frame 1048574) and ended
in a traceback beyond int32."""
import os
import subprocess
import sys

import pytest

import dacrt

from . import conftest


@pytest.mark.parametrize("frame", ["2000000", "-1048575", "99999999999"])
def test_a_frame_outside_blenders_range_is_refused(frame, tmp_path):
    # (this process's native module, where the shared venv may hold none or an older one)
    site = os.path.dirname(os.path.dirname(dacrt.__file__))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([site, str(conftest.ROOT)]))
    out = subprocess.run([sys.executable, "-m", "addon.cli", "render", "--frame", frame, "--samples", "1",
                          "--out", str(tmp_path / "x.png")], cwd=str(tmp_path), capture_output=True, text=True,
                         timeout=600, env=env)
    assert out.returncode != 0 and "Traceback" not in out.stderr, out.stderr
    assert "error: --frame must be within Blender's frame range -1048574 .. 1048574" in out.stderr, out.stderr
    assert not (tmp_path / "x.png").exists()
