"""The first progressive block of a heavy frame is a one-sample preview, then the block the
triangle count asks for (to amortise the tracer's partitioning): that block alone had been
first, so bmw27 at 240x135 showed nothing, gave no progress and kept no sample for its 32 spp
(1M paths, 3-5 s). The rule of the sizes, not timings."""
import numpy as np
import pytest

from addon import integrator
from addon import scenedata as sd
from addon.integrator import Integrator, first_blocks

from . import scenes

M = 1 << 20


@pytest.mark.parametrize('triangles, pixels, want', [
    (1_680_000, 240 * 135, (240 * 135, M)),         # bmw27 at 50%: 1 spp, then 1M paths (was 32 spp first)
    (1_680_000, 480 * 270, (1 << 16, M)),           # a big frame: a run of pixels of the first sample
    (1_680_000, 8 * 6, (1 << 14, M)),               # a tiny frame: at least _MIN_PATHS
    (100_000, 160 * 120, (400_000, None)),          # the dragon: a 400K-path block is quick (0.25 s)
    (200_000, 160 * 120, (160 * 120, 800_000)),
    (1_000, 160 * 120, (1 << 16, None)),            # a small scene: _FIRST_PATHS alone, as before
    (20_000, 320 * 240, (80_000, None)),            # under two previews of 65,536 paths: as before
])
def test_first_blocks(triangles, pixels, want):
    assert first_blocks(triangles, pixels) == want
    first, then = want
    assert first <= max(pixels, 1 << 14) or then is None      # the preview is at most one sample


@pytest.mark.parametrize('samples, want', [(4, None), (16, None), (20, (240 * 135, M))])
def test_no_preview_where_the_whole_render_is_a_quick_first_block(samples, want):
    """bmw27 at 240x135: at 4 and 16 spp the render is one block of under _PREVIEW_FROM paths,
    so a preview would only add a batch (a benchmark point, an animation frame)."""
    total = 240 * 135 * samples
    assert first_blocks(1_680_000, 240 * 135, total) == (want or (M, None))


def _heavy(width, height, samples):
    """An icosphere of 81,920 triangles filling an orthographic view: 4 paths a triangle ask
    for 327,680-path blocks, far more than the frame's pixels."""
    v, t = scenes.icosphere(1.0, subdiv=6)
    geometry = scenes.geometry([(v, t, 1, scenes.ALL_VIS)])
    cam = scenes.ortho_down(height=3.0, width=width, px=height, view=2.4)
    return sd.SceneData(cam, geometry, [scenes.material('default'), scenes.material('grey', (0.5, 0.5, 0.5))],
                        [], np.full(3, 0.3, np.float32), sd.Settings(samples=samples, max_bounces=2))


def test_a_heavy_frame_shows_a_preview_sample_first_then_takes_the_amortising_block(monkeypatch):
    monkeypatch.setattr(integrator, '_PREVIEW_FROM', 1 << 15)      # (a test-sized heavy frame)
    integ = Integrator(_heavy(32, 24, 64))
    done = [p.samples_done for p in integ.passes()]
    # preview: 16,384 paths = 21 spp of 768 pixels, as equal blocks of the 64: 16; then all
    # the rest in the 327,680-path block (the old first block: all 64 at once)
    assert done == [16, 64], done


def test_a_preview_smaller_than_one_sample_finishes_that_sample_before_the_big_block(monkeypatch):
    monkeypatch.setattr(integrator, '_FIRST_PATHS', 8192)
    monkeypatch.setattr(integrator, '_MIN_PATHS', 4096)
    monkeypatch.setattr(integrator, '_PREVIEW_FROM', 1 << 15)
    integ = Integrator(_heavy(128, 96, 8))          # 12,288 pixels: the preview is 2/3 of a sample
    done = [p.samples_done for p in integ.passes()]
    assert done == [0, 1, 8], done
    assert np.all(integ.film.sample_counts() == 8)


def test_a_render_of_at_most_two_first_blocks_is_one_block():
    """The Cornell box (34 triangles) at 160x120 and 4 spp, 76,800 paths: one block, where the
    equal split of blocks of at most _FIRST_PATHS had made it two of 2 spp, each paying a
    block's fixed costs (its bounces' kernel calls and traces: ~4 ms CPU of a 4-spp outdoor
    render). Longer renders start as before."""
    one = Integrator(scenes.cornell_box(width=160, height=120, samples=4, max_bounces=2))
    assert [p.samples_done for p in one.passes()] == [4]
    longer = Integrator(scenes.cornell_box(width=160, height=120, samples=8, max_bounces=2))
    assert next(longer.passes()).samples_done == 3      # 65,536 paths of 19,200 pixels, equal blocks
