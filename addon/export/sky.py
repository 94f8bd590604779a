"""The world's Sky Texture node (ShaderNodeTexSky) as an environment map: each of its skies is
rendered, as Cycles evaluates it, into an equirectangular radiance image that the environment
light samples by importance: Multiple and Single Scattering by addon/sky.py (sun disc
included), Preetham and Hosek-Wilkie by addon/skyanalytic.py. Part of the export layer."""

from functools import lru_cache

import numpy as np

from .. import scenedata as sd
from .. import sky as model
from .. import skyanalytic
from ..mapping import environment_rotation
from .colorspaces import xyz_to_scene_linear

EVALUATED = ('MULTIPLE_SCATTERING', 'SINGLE_SCATTERING', 'PREETHAM', 'HOSEK_WILKIE')
# 2048 x 1024 texels (0.18 degrees): the default sun (0.545 degrees) spans ~3 of them, and a
# texel's row is finer than the sky's fastest change at the horizon a render resolves
WIDTH = 2048
# Multiple Scattering's rows: the ground's edge (the horizon's dip, 0.32 degrees below at the
# default Altitude of 100 m) is a step Cycles' table resolves in rows of ~0.08 degrees; rows of
# 0.18 degrees blended across it (render rows 0.91x and 1.16x Cycles' there, the ground below
# 1-1.5% bright). Rows of 0.088 degrees: within 2%, a 1-degree band 0.6%. 2048 x 2048, 48 MB;
# single scattering's ground reads the horizon's row, without that step
MULTIPLE_HEIGHT = 2048
ANALYTIC_WIDTH = 1024          # Preetham and Hosek-Wilkie: smooth, no disc
# Hosek-Wilkie's rows: its sqrt(cos theta) term turns sharply at the horizon (where Cycles also
# clamps theta to pi/2 - 0.001), which a row of 0.35 degrees blended across: up to 4.7% bright
# just above the horizon, 0.7% dim at 0.3 degrees, a 1-degree band 0.8% bright. Rows of 0.088
# degrees: 0.7% at most, a 0.25-degree band 0.08%, a 1-degree one 0.02% (+0.3-0.6 s of CPU)
HOSEK_HEIGHT = 2048


# the settings of each sky type that a NaN in makes Cycles' sky black (or crash), measured in 5.0.1
# (a Hosek-Wilkie sky of a NaN Sun Direction is not black there, nor a NaN Sun Intensity)
_SCATTERING_READS = ('sun_rotation', 'air_density', 'aerosol_density', 'ozone_density', 'sun_elevation', 'altitude')
_BLACK_WHEN_NAN = {'MULTIPLE_SCATTERING': _SCATTERING_READS, 'SINGLE_SCATTERING': _SCATTERING_READS,
                   'PREETHAM': ('turbidity', 'sun_direction'), 'HOSEK_WILKIE': ('turbidity', 'ground_albedo')}


def node_sky(node, reasons=None):
    """The model's settings (model.Sky, skyanalytic.Analytic) of a Sky Texture node, else None."""
    if node.sky_type == 'PREETHAM':
        return skyanalytic.Analytic.preetham(tuple(node.sun_direction), float(node.turbidity))
    if node.sky_type == 'HOSEK_WILKIE':
        t = float(node.turbidity)
        if not 1.0 <= t <= 10.0 and reasons is not None:
            reasons.append(f"Sky Texture turbidity {t:g} read as {min(max(t, 1.0), 10.0):g} (the model's range)")
        return skyanalytic.Analytic.hosek_wilkie(tuple(node.sun_direction), t, float(node.ground_albedo))
    if node.sky_type not in EVALUATED:
        return None
    sun_disc = bool(node.sun_disc)
    if sun_disc and np.isnan(node.sun_size):
        # (measured in a test scene: Cycles 5.65, between 2.50 without the disc and 8.51 with
        # a default one: part of the disc's light, which no size here gives)
        sun_disc = False
        if reasons is not None:
            reasons.append(f"Sky Texture '{node.name}': Sun Size is nan; its sun disc is not rendered (Cycles "
                           "renders part of that sun's light)")
    if sun_disc and np.isnan(node.sun_intensity) and reasons is not None:
        # (Cycles 5.0.1 renders it as an intensity of 0, measured on a floor under the sky:
        # 2.2244 against 2.2245 with 0, 12.34 with 1; so does the model here, had silently)
        reasons.append(f"Sky Texture '{node.name}': Sun Intensity is nan; its sun disc gives no light, as in Cycles")
    return model.Sky.from_node_values(
        node.sky_type == 'MULTIPLE_SCATTERING', node.sun_elevation, node.sun_rotation,
        sun_disc=sun_disc, sun_size=float(node.sun_size), sun_intensity=float(node.sun_intensity),
        altitude=float(node.altitude), air=float(node.air_density), aerosol=float(node.aerosol_density),
        ozone=float(node.ozone_density))


def sky_environment(node, strength, reasons, chain=None):
    """(uniform radiance (3,), scenedata.Environment) of a Sky Texture feeding a Background of
    `strength`, its Vector through a Mapping rotation as an Environment Texture's; None when
    its type is not evaluated (the caller reports it). chain: the colour nodes after it,
    fn((n, 4) RGBA) -> (n, 3) (nodeeval.compile_image_chain), applied to its map."""
    # a script's or driver's NaN in a setting the sky reads: Cycles renders the sky black
    # (3e-7 over a lit floor) or crashes (a scattering sky's Sun Elevation or Altitude: a
    # segfault in 5.0.1); the export had failed ("index -9223372036854775808 is out of bounds",
    # "environment map: pixel value nan ...", "cannot convert float NaN to integer"), and a
    # Preetham sky of a NaN Sun Direction rendered lit (0.53)
    nan = [node.bl_rna.properties[k].name for k in _BLACK_WHEN_NAN.get(node.sky_type, ())
           if np.isnan(getattr(node, k)).any()]
    if nan:
        crashes = [n for n in nan if n in ('Sun Elevation', 'Altitude')]
        reasons.append(f"Sky Texture '{node.name}': {', '.join(nan)} {'is' if len(nan) == 1 else 'are'} nan; "
                       "the sky is rendered black " + (f"(Cycles 5.0.1 crashes on a NaN {' or '.join(crashes)})"
                                                       if crashes else "(as in Cycles)"))
        return np.zeros(3, np.float32), None
    sky = node_sky(node, reasons)
    if sky is None:
        return None
    if not (np.isfinite(strength) and strength >= 0):
        reasons.append(f"Background Strength {float(strength):g} is negative or not finite; rendered black")
        return np.zeros(3, np.float32), None
    m = xyz_to_scene_linear()
    m = tuple(map(tuple, model.XYZ_TO_REC709 if m is None else m))
    img = _image(sky, m) if chain is None else _make_image(sky, m, _rgb_chain(chain))
    # Blender 5.0 makes the Vector input unavailable while the sun disc is on: Cycles then
    # reads the view direction whatever is linked to it
    vector = node.inputs.get('Vector')
    mapped = []
    rotation = environment_rotation(node, mapped, vector=vector is not None and vector.enabled)
    reasons.extend(f"Sky Texture '{node.name}': {r}" for r in mapped)
    env = sd.Environment(img, np.full(3, strength, np.float32), rotation, 'Linear',
                         texels_key=None if chain is not None else ('sky', sky, m))
    return np.zeros(3, np.float32), env


@lru_cache(maxsize=4)
def _image(sky, xyz_to_rgb):
    """The sky's equirectangular image (read-only), kept for the next render of the same sky
    (frames of an animation, the viewport's redraws): ~0.3-0.8 s to make, 25-48 MB."""
    img = _make_image(sky, xyz_to_rgb)
    img.setflags(write=False)
    return img


def _make_image(sky, xyz_to_rgb, chain=None):
    if isinstance(sky, skyanalytic.Analytic):
        img = skyanalytic.equirect(sky, ANALYTIC_WIDTH, np.array(xyz_to_rgb), HOSEK_HEIGHT if sky.hosek else None)
        if chain is not None:
            img = chain(img.reshape(-1, 3)).reshape(img.shape).astype(np.float32)
        return img
    return model.equirect(sky, WIDTH, np.array(xyz_to_rgb), chain=chain,
                          height=MULTIPLE_HEIGHT if sky.multiple else None)


def _rgb_chain(chain):
    """fn((n, 3) RGB) -> (n, 3) of a colour-node chain on RGBA texels (alpha 1), its results
    made finite and non-negative (a world's radiance)."""
    def rgb(px):
        y = np.asarray(chain(np.concatenate([px, np.ones_like(px[:, :1])], axis=1)), np.float64)
        y = np.broadcast_to(y.reshape(len(px), -1), (len(px), 3))
        return np.maximum(np.nan_to_num(y, nan=0.0, posinf=0.0, neginf=0.0), 0.0)
    return rgb


def sun_beside_legacy_said(nodes):
    """What to say where the world's shader holds a Multiple Scattering sky's sun disc and a
    Preetham or Hosek-Wilkie Sky Texture (nodes: the Sky Texture nodes it reads), or ''. Cycles 5.0.1
    renders such a world's light darker than the sum of its parts: an Add of the two skies lit a
    diffuse ground 0.956-0.963x Cycles' renders of each sky alone added (fuzz seed 432, a Mix of
    them 0.954-0.960x a quadrature of the world), where DACRT's agrees with both within 0.1%;
    without the disc, or beside a constant or a disc-less Multiple Scattering sky, they agree."""
    disc = [n for n in nodes if n.sky_type == 'MULTIPLE_SCATTERING' and n.sun_disc]
    legacy = [n for n in nodes if n.sky_type in ('PREETHAM', 'HOSEK_WILKIE')]
    if not disc or not legacy:
        return ''
    return (f"world has the sun disc of Sky Texture '{disc[0].name}' beside the "
            f"{legacy[0].sky_type.replace('_', '-').title()} Sky Texture '{legacy[0].name}': Cycles lights "
            "the scene ~4% darker from such a world than from its parts (measured), DACRT as its parts")

