"""Running render jobs in a bpy worker process (renderworker.py) from a benchmark's process,
which never imports Blender itself.

One worker per engine and benchmark run: the job list goes in as a JSON file, results come
back as JSON lines (followed live for the progress bar) and .npy images in a work folder.
Blender's own chatter goes to a log file, whose tail is shown if the worker fails.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

from .renderspec import REPO


class WorkerError(RuntimeError):
    """expected: the worker refused the scene or the arguments with a reason (a ValueError),
    said in the message; otherwise a failure, whose log the message names."""

    def __init__(self, message, expected=False):
        super().__init__(message)
        self.expected = expected


class Unavailable(Exception):
    """The worker reported that it cannot render this engine here (a reason, not a failure)."""


def run_jobs(engine: str, renders: list[dict], workdir: Path, progress=None, label: str = ""):
    """Render `renders` with `engine` in one bpy worker; returns the result records in order.
    progress: a Progress whose step() is called per finished render (warm-ups excluded)."""
    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    stamp = f"{engine.lower()}-{int(time.time() * 1000)}"
    job_path, res_path = workdir / f"job-{stamp}.json", workdir / f"results-{stamp}.jsonl"
    log_path = workdir / f"worker-{stamp}.log"
    job = dict(engine=engine, outdir=str(workdir), results=str(res_path), renders=renders)
    job_path.write_text(json.dumps(job))
    res_path.write_text("")
    records, pos = [], 0
    with open(log_path, "w") as log:
        proc = subprocess.Popen([sys.executable, "-m", "tests.bench.renderworker", str(job_path)],
                                cwd=REPO, stdout=log, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL)
        try:
            while True:
                done = proc.poll() is not None
                with open(res_path) as f:
                    f.seek(pos)
                    chunk = f.read()
                lines = chunk.split("\n")
                pos += len(chunk) - len(lines[-1])       # keep a partial last line for later
                for line in lines[:-1]:
                    if not line.strip():
                        continue
                    rec = json.loads(line)
                    if "error" in rec:
                        if rec.get("expected"):         # the reason alone: no log to keep
                            raise WorkerError(f"{engine} worker failed: {rec['error']}", expected=True)
                        raise WorkerError(f"{engine} worker failed: {rec['error']} (log: {log_path})"
                                          + _tail(log_path))
                    if "unavailable" in rec:
                        raise Unavailable(rec["unavailable"])
                    records.append(rec)
                    if progress is not None:
                        progress.step()
                        progress.show(f"{label}{engine} {rec['scene']} {rec['samples']} spp "
                                      f"seed {rec['seed']}: {rec['seconds']:.2f} s")
                if done:
                    break
                time.sleep(0.2)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    if proc.returncode != 0 or len(records) != len(renders):
        raise WorkerError(f"{engine} worker exited with status {proc.returncode} after "
                          f"{len(records)} of {len(renders)} renders (log: {log_path})"
                          f"{_tail(log_path)}")
    job_path.unlink(missing_ok=True)
    return records


def _tail(path: Path, n: int = 15) -> str:
    try:
        lines = path.read_text(errors="replace").splitlines()[-n:]
    except OSError:
        return ""
    return "\n    " + "\n    ".join(lines)
