"""The rendering benchmarks' worker pays its one-off costs before the renders it times: every
timed render comes after a warm-up render of the same scene and sample count whose image was
saved and read back like a timed one's. A worker that saved its first image only after its first
timed render charged that save's one-offs (OpenImageIO's import, whose allocations took the free
blocks the render had left in the held heap) to the next timed render: a fresh worker's second
dragon render at 4 spp faulted ~25 MB in again, every time.

The worker's render and save steps are replaced by recorders here (bpy itself is not run): the
property is the order of the steps, whatever a render costs on this machine."""
from types import SimpleNamespace

import numpy as np
import pytest

from tests.bench import renderworker
from tests.bench.renderspec import builtin_spec


class _Steps:
    """The worker's steps in order: ('render', samples, seed) and ('save',)."""

    def __init__(self):
        self.log, self.samples, self.seed = [], None, None


@pytest.fixture
def steps(monkeypatch):
    rec = _Steps()

    def configure(scene, spec, engine, samples, seed):
        rec.samples, rec.seed = samples, seed

    def render():
        rec.log.append(('render', rec.samples, rec.seed))

    def save(scene, path):
        rec.log.append(('save',))
        return np.zeros((2, 2, 4), np.float32)

    monkeypatch.setattr(renderworker.renderscenes, "build", lambda spec: object())
    monkeypatch.setattr(renderworker.renderscenes, "configure", configure)
    monkeypatch.setattr(renderworker, "bpy", SimpleNamespace(ops=SimpleNamespace(render=SimpleNamespace(render=render))))
    monkeypatch.setattr(renderworker, "_save_exr", save)
    return rec


def _job(tmp_path, renders):
    return dict(engine="CYCLES", outdir=str(tmp_path / "out"), results=str(tmp_path / "results.jsonl"),
                renders=renders)


def _timed(log, seeds):
    """Indices in log of the timed renders (those of the job's own seeds)."""
    return [i for i, step in enumerate(log) if step[0] == 'render' and step[2] in seeds]


@pytest.mark.parametrize("warmup", ["point", True])
def test_every_timed_render_follows_a_saved_warm_up(steps, tmp_path, warmup):
    spec = builtin_spec("cornell").as_dict()
    renders = [dict(spec=spec, samples=spp, seed=seed, warmup=warmup, image=None)
               for spp in (4, 16) for seed in range(3)]
    renderworker.run(_job(tmp_path, renders))
    log = steps.log
    timed = _timed(log, {0, 1, 2})
    assert len(timed) == 6
    first = timed[0]
    warm = [i for i in range(first) if log[i][0] == 'render']
    assert warm, log
    # the save of a warm-up's image precedes the first timed render
    assert any(log[i] == ('save',) for i in range(warm[0] + 1, first)), log
    if warmup == "point":
        # each sample count's first timed render follows a warm-up at that count, then a save
        for spp in (4, 16):
            i = next(i for i in timed if log[i][1] == spp)
            w = max(j for j in range(i) if log[j][0] == 'render' and log[j][2] == 999)
            assert log[w][1] == spp and ('save',) in log[w + 1:i], log
