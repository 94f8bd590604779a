"""The Single Scattering sky's ground (below the horizon) as Cycles 5.0.1 renders it.

intern/sky fills the lower half of the single-scattering table with its horizon row x
(1 - 2.5 z)^3 (z the sine of the row's warped elevation, black from 0.4), and Cycles 5.0.1
reads the ground from those rows as it reads Multiple Scattering's (the warp undone, bilinear).
DACRT had faded the row at y 0.508 by the view's own z (the kernel's published branch): its
ground rendered 1.01x Cycles' just below the horizon to 1.25x at -19.5 degrees (an
equirectangular view, row by row), a camera 10-40 degrees down 1.08x; here bands up to 1.11x,
the image 1.019x (now within 0.1% and 0.03%).

A 48 x 36 camera 12 degrees down (the horizon near the top, -27 degrees at the bottom): each
channel's mean over bands of 4 rows within 1% of Cycles' where it is brighter than 1/50 of its
brightest band (the fade's tail, darker, is noise against it); the whole image's mean within
0.5%."""
import math

import numpy as np
import pytest

from .skyview import both_engines, sky_view

pytestmark = pytest.mark.usefixtures('parity_addon')


@pytest.mark.parametrize('sun, air', ((30.0, 1.0), (5.0, 2.5)))
def test_ground_below_the_horizon(sun, air, tmp_path):
    sky_view((48, 36), 78.0, sky_type='SINGLE_SCATTERING', sun_elevation=math.radians(sun), air_density=air)
    rows = {e: img.mean(axis=1) for e, img in both_engines(tmp_path, 16, 'BLACKMAN_HARRIS', 1.5).items()}
    c, d = rows['CYCLES'], rows['DACRT']                        # (rows, 3), row 0 at the bottom
    bands = [slice(i, i + 4) for i in range(0, 36, 4)]
    cb, db = (np.array([x[b].mean(0) for b in bands]) for x in (c, d))      # (bands, 3)
    lit = cb > cb.max(axis=0) / 50          # (a low sun in dense air leaves the blue black)
    ratio = db[lit] / cb[lit]
    assert lit.sum() >= 10 and np.abs(ratio - 1).max() < 0.01, (lit.sum(), (db / cb).round(4).tolist())
    seen = c.mean(0) > 0
    ratio = d.mean(0)[seen] / c.mean(0)[seen]
    assert np.abs(ratio - 1).max() < 0.005, ratio.round(4).tolist()


def test_sun_disc_across_the_horizon(tmp_path):
    """The sun at 0.1 degrees, its disc (0.545 degrees) partly below the horizon: Cycles 5.0.1
    draws the part below too, down to the Earth's edge (-0.32 degrees at 100 m), as for Multiple
    Scattering. DACRT had hidden it below z = 0 for Single Scattering (the kernel's published
    branch): the light in a 2.5-degree frame about it 0.81x Cycles'; now within 0.5%
    (measured 1.002x). The frame's lower half is not compared: the map spreads the disc over
    ~3 texels and blends them (measured there 1.17x Cycles', Multiple Scattering's 1.07x)."""
    sky_view((32, 32), 90.0, lens=825.0, sky_type='SINGLE_SCATTERING', sun_elevation=math.radians(0.1),
             sun_rotation=0.0)
    img = both_engines(tmp_path, 16, 'BOX', 1.0)
    c, d = (img[e].mean(axis=(0, 1)) for e in ('CYCLES', 'DACRT'))
    assert c[0] > 100 and np.abs(d[:2] / c[:2] - 1).max() < 0.005, (c.round(3).tolist(), d.round(3).tolist())
