"""Progressive passes are sized by the render's own speed, not by the wall time other processes
hold the cores: on a machine loaded by other renders, builds and tests, the wall-time rate had
cut a Cornell box at 64 spp into 16K-40K-path passes that cost 0.58 s CPU, against 0.44-0.47 s
in 320K-1.2M-path passes (each bounce's kernel calls, traces and shadow batches have fixed
costs). A pass's time is the smaller of its wall and CPU time. The rule of the sizes, with the
clocks the integrator reads replaced, not timings."""
import itertools
from types import SimpleNamespace

from addon import integrator
from addon.integrator import Integrator

from . import scenes


def _clocks(wall_wait, cpu_wait):
    """The integrator's clocks, each call `*_wait` seconds after the last (a process waiting
    for the cores: wall time passes, its CPU time does not). Fake alone, not added to the real
    clocks: the real time a pass took on a loaded machine had moved the sizes (a run of the
    suite at load 8 cut 43 spp where 44 was due)."""
    walls, cpus = itertools.count(1), itertools.count(1)
    return SimpleNamespace(perf_counter=lambda: wall_wait * next(walls),
                           process_time=lambda: cpu_wait * next(cpus))


def _samples_done(monkeypatch, wall_wait, cpu_wait):
    # 3,072 pixels at 64 spp: a first block of 16 spp (65,536 paths as equal blocks), then
    # blocks as the measured speed allows, at most 4x the last (here the 48 spp left)
    monkeypatch.setattr(integrator, 'time', _clocks(wall_wait, cpu_wait))
    integ = Integrator(scenes.cornell_box(width=64, height=48, samples=64, max_bounces=2))
    return [p.samples_done for p in integ.passes()]


def test_a_pass_waiting_for_the_cores_does_not_shrink_the_next(monkeypatch):
    """Every clock read a second late in wall time only (the cores held by other processes):
    the passes are the ones the render's CPU time asks for. Before, each pass took seconds of
    wall time, so the next was cut to ~40,000 paths (12 spp) each."""
    assert _samples_done(monkeypatch, 1.0, 0.0) == [16, 64]


def test_a_slow_render_still_gets_passes_of_its_time(monkeypatch):
    """A pass slow in CPU time as well (a heavy scene) is a slow pass: each next one is cut to
    0.8 s of the last's speed, down to _MIN_PATHS (16,384 paths: 5 spp), as before."""
    assert _samples_done(monkeypatch, 1.0, 1.0) == [16, 28, 37, 44, 49, 54, 59, 64]
