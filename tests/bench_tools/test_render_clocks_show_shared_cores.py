"""The rendering benchmarks record, beside each render's wall seconds, the worker's own CPU seconds
and the CPU seconds other processes used meanwhile, and errortime names the points that rendered
while other processes held cores. A render's 2-thread tracer calls wait at their joins for a
core another process holds, so its wall time grows with no change in its work: errortime's
Cornell at 4-64 spp took 1.5x the wall time of another run of the same tracer code, its tracer's
thread-seconds equal to its wall seconds where they were 1.6x in the points after, and nothing in
the output said so (the load average, a one-minute mean read at start and end, had been 1.3).

The worker's render step is replaced here (bpy itself is not run): one render burns CPU in the
worker, one waits while a child process burns CPU."""
import json
import subprocess
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

from tests.bench import errortime, renderworker, report
from tests.bench.renderspec import builtin_spec

BURN = 0.15     # seconds of CPU each busy step uses


def _burn(seconds):
    end = time.process_time() + seconds
    x = 0
    while time.process_time() < end:
        x += 1
    return x


def _child_burns():
    subprocess.run([sys.executable, "-c",
                    f"import time\nend = time.process_time() + {BURN}\n"
                    "while time.process_time() < end: pass"], check=True)


@pytest.fixture
def worker(monkeypatch):
    steps = {}

    def configure(scene, spec, engine, samples, seed):
        steps["seed"] = seed

    def render():
        if steps["seed"] == 0:
            _burn(BURN)             # the render's own work
        elif steps["seed"] == 1:
            _child_burns()          # another process's work while the render waits

    monkeypatch.setattr(renderworker.renderscenes, "build", lambda spec: object())
    monkeypatch.setattr(renderworker.renderscenes, "configure", configure)
    monkeypatch.setattr(renderworker, "bpy", SimpleNamespace(ops=SimpleNamespace(render=SimpleNamespace(render=render))))
    monkeypatch.setattr(renderworker, "_save_exr", lambda scene, path: np.zeros((2, 2, 4), np.float32))


def test_each_render_records_its_own_cpu_and_the_cpu_others_used(worker, tmp_path):
    spec = builtin_spec("cornell").as_dict()
    job = dict(engine="CYCLES", outdir=str(tmp_path / "out"), results=str(tmp_path / "r.jsonl"),
               renders=[dict(spec=spec, samples=4, seed=s, warmup=False, image=None) for s in (0, 1)])
    renderworker.run(job)
    own, waited = [json.loads(line) for line in open(job["results"])]
    # the burning render: its CPU seconds are its work, at most its wall time on one thread
    assert own["cpu_seconds"] >= 0.9 * BURN
    assert own["cpu_seconds"] <= own["seconds"] + 0.02
    # the waiting render: almost no CPU of its own, the child's counted as others' (the kernel's
    # 10 ms tick is the resolution; other processes on a shared machine only add to it)
    assert waited["cpu_seconds"] < 0.5 * BURN
    assert waited["others_cpu_seconds"] is not None
    assert waited["others_cpu_seconds"] >= 0.8 * BURN - 0.02
    assert waited["seconds"] >= 0.9 * BURN


def _rec(spp, seed, seconds, others):
    return dict(scene="cornell", engine="DACRT", samples=spp, seed=seed, seconds=seconds,
                relmse=0.1 / spp, others_cpu_seconds=others)


def test_errortime_names_the_points_rendered_beside_other_processes(capsys):
    recs = [_rec(4, s, 0.04, 0.03) for s in range(3)]        # 0.75 cores held by others
    recs += [_rec(16, s, 0.10, 0.01) for s in range(3)]      # 0.1 cores: not named
    recs += [_rec(64, s, 0.30, None) for s in range(3)]      # no /proc/stat: not named
    summary = errortime.summarise(recs, {})
    pts = {p["samples"]: p for p in summary["cornell"]["DACRT"]["points"]}
    assert pts[4]["others_cores"] == pytest.approx(0.75)
    assert pts[16]["others_cores"] == pytest.approx(0.1)
    assert "others_cores" not in pts[64]
    doc = dict(summary=summary, references={}, notes=[],
               settings=dict(eps=1e-3, ref_samples=1024, ref_seeds=4, seeds=3),
               machine=dict(load_avg_start=1.0, load_avg_end=1.0, cores=2), when="now")
    assert report.shared_points(doc) == [("cornell", "DACRT", 4, pytest.approx(0.75))]
    report.print_errortime(doc)
    out = capsys.readouterr().out
    assert "cornell DACRT 4 spp (0.75 cores)" in out
    assert "16 spp (" not in out
    md = report.errortime_markdown(doc)
    assert "Other processes held 0.75 cores on average during cornell DACRT 4 spp." in md
    assert "during cornell DACRT 16 spp" not in md
