"""A Bump whose Distance or Strength is near float32's limit renders as Cycles' float32 bump:
svm_node_set_bump's vector BUMP_DX |det| N - scale surfgrad has a squared length past
float32's largest from a Distance of about 1e22-1e24 at a pixel's footprint, its safe_normalize
gives 0 and Cycles keeps the normal unbent; a Strength of 3.4e38 overflows the length of the
blend, a zero normal the closure replaces by N. DACRT bent in float64 and had rendered the bump
(a Wave under a sun: mean 0.09 against Cycles' flat 0.64) and black for the Strength."""
import pytest

from .test_bump import _bumped, _compare, _plane_scene, _render, _wave

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('strength, distance, flat', [
    (1.0, 1e20, False),         # (control: bent in both engines, the normals nearly in the plane)
    (1.0, 1e24, None),          # (partly: unbent where the height's slope is steep enough)
    (1.0, 1e26, True),
    (1.0, -3.4e38, True),
    (3.4e38, 1.0, True),
], ids=['1e20', '1e24', '1e26', '-max', 'strength-max'])
def test_a_bump_past_float32_is_unbent_as_in_cycles(strength, distance, flat, tmp_path):
    img, nrm = _render(_plane_scene(lambda: _bumped("Waves", _wave(), 'Fac', strength=strength,
                                                    distance=distance)), tmp_path)
    _compare(img, nrm)
    up = nrm['CYCLES'][..., 2]          # (the plane's normal is +z)
    if flat is True:
        assert up.mean() > 0.99, "Cycles leaves the normal unbent here (but where the slope is near 0)"
    elif flat is False:
        assert up.mean() < 0.1, "the relief must bend the normals"
    else:
        assert 0.3 < (up > 0.999).mean() < 0.99, "both bent and unbent pixels must show"
