"""Pure summaries of the benchmarks: partition scoring, error-vs-time aggregation, the display
conversion of `compare`; and their argument checks."""
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.bench import compare, errortime, partition


ROOT = Path(__file__).resolve().parents[2]


def _case(times):
    return dict(configs={n: dict(min_s=t, median_s=t) for n, t in times.items()})


def test_partition_score_is_the_geometric_mean_of_time_over_best():
    cases = [_case({"median": 1.0, "sah": 2.0, "adaptive 2": 1.0}),
             _case({"median": 4.0, "sah": 1.0, "adaptive 2": 2.0})]
    s = partition.score(cases, ["median", "sah", "adaptive 2"])
    assert s["median"] == pytest.approx(2.0)          # sqrt(1 * 4)
    assert s["sah"] == pytest.approx(np.sqrt(2.0))    # sqrt(2 * 1)
    assert s["adaptive 2"] == pytest.approx(np.sqrt(2.0))
    name, ratio = partition.best_ratio({"median": 1.0, "adaptive 4": 1.2, "adaptive 0.5": 1.1})
    assert (name, ratio) == ("adaptive 0.5", 0.5)
    names = [c["name"] for c in partition.configs([1, 2.5])]
    assert names == ["median", "sah", "adaptive 1", "adaptive 2.5"]


def _rec(engine, spp, seed, seconds, rel):
    return dict(scene="s", engine=engine, samples=spp, seed=seed, seconds=seconds, relmse=rel)


def test_errortime_summary_keeps_what_dacrt_reported_once():
    """What DACRT said about a scene (e.g. an empty one, black in both engines) must
    reach the summary (it was dropped), once per scene, without the materials line."""
    said = ["the scene has no renderable geometry; only the world background is rendered",
            "2 material(s) approximated as diffuse: 'A'"]
    native = dict(seconds=0.01, filter_seconds=0.0, partition_seconds=0.0, leaf_seconds=0.0)
    breakdown = dict(wall_seconds=0.1, native=native, warnings=said)
    recs = [dict(_rec("DACRT", spp, seed, 0.1, 0.01 / spp), breakdown=breakdown, memory=dict(peak_above_start_mib=1))
            for spp in (1, 2) for seed in range(2)] + [_rec("CYCLES", 1, 0, 0.1, 0.01)]
    s = errortime.summarise(recs, {})["s"]
    assert s["dacrt_reports"] == [said[0]]


def test_errortime_summary_means_efficiency_and_equal_error():
    recs = []
    for seed in range(2):
        for spp in (4, 16):
            recs.append(_rec("CYCLES", spp, seed, spp * 0.1, 1.0 / spp))
            recs.append(_rec("DACRT", spp, seed, spp * 0.05, 1.0 / spp))  # twice as fast
    s = errortime.summarise(recs, {})["s"]
    cyc = s["CYCLES"]["points"]
    assert [p["samples"] for p in cyc] == [4, 16]
    assert cyc[0]["seconds"] == pytest.approx(0.4) and cyc[0]["relmse"] == pytest.approx(0.25)
    assert cyc[0]["efficiency"] == pytest.approx(1 / (0.25 * 0.4))
    assert s["CYCLES"]["slope"] == pytest.approx(-1.0)
    ratios = [q["ratio"] for q in s["equal_error"] if q["engine"] == "DACRT"]
    assert ratios == pytest.approx([0.5, 0.5])


def test_display_conversion_and_difference():
    lin = np.zeros((2, 1, 4))
    lin[0, 0, :3] = 1.0          # bottom row white
    lin[1, 0, :3] = 0.0018       # top row, linear segment of the sRGB curve
    out = compare.to_display(lin)
    assert out.dtype == np.uint8 and out.shape == (2, 1, 3)
    assert out[1, 0].tolist() == [255, 255, 255]   # flipped: row 0 of the PNG is the top
    assert out[0, 0, 0] == round(12.92 * 0.0018 * 255)
    d = compare.difference_image(lin, np.zeros_like(lin), gain=16)
    assert d[1, 0].tolist() == [255] * 3
    assert compare.channel_mean_ratio(lin * 2 + 0.0, lin)[0] == pytest.approx(2.0)


def test_blend_materials_mode_is_checked_and_keys_the_cycles_reference(tmp_path):
    from tests.bench import renderspec
    blend = tmp_path / "shot.blend"
    blend.write_bytes(b"BLENDER")
    fair = renderspec.scene_spec(str(blend))
    assert fair.materials == "diffuse"
    as_is = renderspec.scene_spec(str(blend), materials="as-is")
    with pytest.raises(ValueError, match="materials"):
        renderspec.scene_spec(str(blend), materials="glossy")
    # Cycles renders different materials in the two modes: their references must not be shared
    assert renderspec.reference_key(fair, 64, [0]) != renderspec.reference_key(as_is, 64, [0])
    assert renderspec.reference_key(fair, 64, [0]) == renderspec.reference_key(
        renderspec.scene_spec(str(blend)), 64, [0])
    assert renderspec.scene_spec("cornell").blend is None      # built-in scenes are diffuse already


def test_compare_prints_what_dacrt_reported_beyond_its_materials(capsys):
    """A world node DACRT does not evaluate (a Sky Texture, rendered 0.3x Cycles) was said only
    in the render's log: compare printed the materials' approximations alone."""
    compare._print_warnings(["world approximated: Sky Texture not evaluated",
                             "2 material(s) approximated as diffuse: A, B"])
    out = capsys.readouterr().out
    assert "DACRT reports: world approximated: Sky Texture not evaluated" in out
    assert "material(s)" not in out          # those are listed per material by _print_materials


@pytest.mark.parametrize('argv, message', [
    (['skips', '--repeat', '0'], '--repeat must be >= 1'),
    (['skips', '--samples', '-3'], '--samples must be >= 1'),
    (['skips', 'nosuch'], "unknown scene 'nosuch'"),
    (['tracer', '--seed', '-1'], '--seed must be >= 0'),
    (['scaling', '--seed', '-1'], '--seed must be >= 0'),
    (['partition', '--seed', '-1'], '--seed must be >= 0'),
    (['errortime', '--json', '/dev/null/x.json'], 'cannot write /dev/null/x.json'),
    (['tracer', '--json', '/dev/null/x.json'], 'cannot write /dev/null/x.json'),
])
def test_bad_benchmark_arguments_are_refused_before_any_work(argv, message):
    """A helper's review: these ran (a negative seed failed deep in numpy, --repeat 0 in a
    KeyError, --samples -3 rendered at 1 spp and said -3, an unwritable --json only after the
    whole run); each is now one line naming the argument, exit 2, before any scene is built."""
    out = subprocess.run([sys.executable, '-m', 'tests.bench', *argv], cwd=str(ROOT), capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 2 and message in out.stderr, out.stderr
    assert 'Traceback' not in out.stderr
