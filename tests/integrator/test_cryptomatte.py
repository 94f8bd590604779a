"""Cryptomatte (addon/cryptomatte.py): the IDs (MurmurHash3_32 and Cycles' hash-to-float), the
sparse coverage sums against a dense count, and the passes of rendered scenes: opaque halves
of a pixel row, assets by parent, and coverage through a transparent sheet."""
import numpy as np
import pytest

from addon import cryptomatte as cm
from addon import scenedata as sd
from .scenes import ALL_VIS, geometry, material, ortho_down, quad, render
from .test_transparency import sheet_scene


def test_murmur3_known_vectors_and_float_ids():
    # MurmurHash3_x86_32's published test vectors
    assert cm.murmur3_32("") == 0 and cm.murmur3_32("", 1) == 0x514E28B7
    assert cm.murmur3_32("hello") == 0x248BFA47
    assert cm.murmur3_32("The quick brown fox jumps over the lazy dog") == 0x2E4FF723
    assert cm.murmur3_32("Hello, world!", 1234) == 0xFAF6CDB3
    assert cm.murmur3_32("é€") == cm.murmur3_32("é€".encode().decode())   # UTF-8 bytes
    # exponent 0 and 255 are moved to 1 and 254: never 0, denormal, inf or NaN
    for h in (0, 0x007FFFFF, 0x7F800000, 0xFFFFFFFF, 0x80000001):
        f = cm.hash_to_float(h)
        assert np.isfinite(f) and abs(f) >= np.finfo(np.float32).tiny
        bits = int(np.array([f], np.float32).view(np.uint32)[0])
        assert bits & 0x807FFFFF == h & 0x807FFFFF              # sign and mantissa kept
    h = cm.murmur3_32("Cube")
    assert cm.hash_to_float(h) == np.array([h], np.uint32).view(np.float32)[0]   # a normal exponent
    meta = cm.metadata("ViewLayer", "CryptoObject", ["Cube", "Ball", "Cube"])
    key = f"cryptomatte/{cm.murmur3_32('ViewLayer.CryptoObject'):08x}"[:19]
    assert meta[key + "/name"] == "ViewLayer.CryptoObject" and meta[key + "/hash"] == "MurmurHash3_32"
    assert meta[key + "/manifest"] == '{"Cube":"%08x","Ball":"%08x"}' % (h, cm.murmur3_32("Ball"))
    assert cm.pass_names("CryptoAsset", 6) == ["CryptoAsset00", "CryptoAsset01", "CryptoAsset02"]
    assert len(cm.pass_names("CryptoAsset", 7)) == 4 and len(cm.pass_names("CryptoAsset", 40)) == 8


def test_manifest_is_written_byte_for_byte_as_cycles_writes_it():
    """Blender writes each name raw between quotes (UTF-8, no JSON escapes; measured from a
    Cycles render of cubes of these names). JSON's \\u00fc escapes had made Blender's
    Cryptomatte node name a picked 'Würfel' as 'Wu00fcrfel'."""
    names = ['Würfel', 'a"b', 'back\\slash', 'tab\tx', '日本', 'Würfel']
    assert cm.manifest(names) == ('{"Würfel":"c959a2b5","a"b":"5187c5ed","back\\slash":"aa5ce9ed",'
                                  '"tab\tx":"eda96a93","日本":"c4d9f942"}')


def _cycles_slots(events, slots):
    """Cycles' film_write_cryptomatte_slots and film_sort_cryptomatte_slots, one write at a
    time: events [(ID index, weight)] of one pixel, in order -> [(ID index, weight)]."""
    table = []
    for i, w in events:
        if w == 0:
            continue
        for s in range(slots):
            if s == len(table):
                table.append([i, w])
                break
            if table[s][0] == i or s == slots - 1:
                table[s][1] += w
                break
    for s in range(1, len(table)):                  # insertion sort, heaviest first
        j = s
        while j > 0 and table[j][1] > table[j - 1][1]:
            table[j], table[j - 1] = table[j - 1], table[j]
            j -= 1
    return table


@pytest.mark.parametrize('nid', [3, 9])
def test_coverage_ranks_match_cycles_slots(nid):
    """More IDs in a pixel than slots (nid 9): the last slot collects the weight of every ID
    that arrives after the slots are taken, as Cycles' does; fewer (3): the plain sums."""
    rng = np.random.default_rng(3)
    npix, slots = 50, 4
    cov, events = cm.Coverage(nid), [[] for _ in range(50)]
    t = 0
    for _ in range(30):                                          # blocks, merged as they come
        k = 700
        pix, idx, w = rng.integers(0, npix, k), rng.integers(0, nid, k), rng.random(k)
        w[::11] = 0.0                                            # zero weights add nothing
        order = t + rng.permutation(k)                           # arrival order within the block
        cov.add(pix, idx, w, order)
        for j in np.argsort(order):
            events[pix[j]].append((idx[j], w[j]))
        t += k
    count = rng.integers(1, 40, npix)
    id_values = cm.ids([f"ob{i}" for i in range(nid)])
    ranks = cov.ranks(npix, count, id_values, slots)
    for p in range(npix):
        table = _cycles_slots(events[p], slots)
        assert np.array_equal(ranks[:len(table), 0, p], id_values[[i for i, _ in table]])
        assert np.allclose(ranks[:len(table), 1, p], [w / count[p] for _, w in table], rtol=1e-6)
        assert np.allclose(ranks[:, 1, p].sum(), sum(w for i, w in events[p]) / count[p], rtol=1e-6)
    assert not cm.Coverage(3).ranks(5, np.ones(5), id_values[:3], 2).any()    # nothing seen: 0


def _two_quads(**settings):
    """Objects A (material 'a') and B (material 'b', child of A's asset 'Rig'): A fills pixel
    columns 0-2 and half of column 3, B the rest of columns 3-6, column 7 sees nothing."""
    a = quad((-2.25, 0.0, 0.0), 1.75, 2.0)                     # x in [-4, -0.5]
    b = quad((1.25, 0.0, 0.0), 1.75, 2.0)                      # x in [-0.5, 3]
    g = geometry([(*a, 1, ALL_VIS), (*b, 2, ALL_VIS)])
    mats = [material('default'), material('mat_a'), material('mat_b')]
    cam = ortho_down(height=0.5, width=8, px=4, view=8.0)
    cam_settings = dict(samples=64, filter_type='BOX', cryptomatte=('CryptoObject', 'CryptoMaterial', 'CryptoAsset'))
    cam_settings.update(settings)
    return sd.SceneData(cam, g, mats, [], np.zeros(3, np.float32), sd.Settings(**cam_settings),
                        object_names=['A', 'B'], object_assets=['Rig', 'Rig'])


def test_one_object_under_two_entries_is_one_cryptomatte_id():
    """An object's instances under instancers of two light groups are two object entries of
    one name: Cryptomatte counts them as the one object (one ID, coverage 1 where both meet)."""
    scene = _two_quads()
    scene.object_names = ['A', 'A']
    img = render(scene).film.cryptomatte_images()["CryptoObject00"]
    assert cm.layer_names(scene, 'CryptoObject') == ['A']
    assert np.all(img[:, :7, 0] == cm.ids(["A"])[0]) and np.allclose(img[:, :7, 1], 1.0)
    assert np.all(img[:, :7, 2:] == 0)


def test_cryptomatte_passes_of_two_quads():
    film = render(_two_quads()).film
    img = film.cryptomatte_images()
    assert sorted(img) == [f"Crypto{k}{i:02d}" for k in ("Asset", "Material", "Object") for i in range(3)]
    ob = img["CryptoObject00"]
    id_a, id_b = cm.ids(["A", "B"])
    assert ob.shape == (4, 8, 4)
    assert np.all(ob[:, :3, 0] == id_a) and np.allclose(ob[:, :3, 1], 1.0) and np.all(ob[:, :3, 2:] == 0)
    assert np.all(ob[:, 4:7, 0] == id_b) and np.allclose(ob[:, 4:7, 1], 1.0)
    edge = ob[:, 3]                                              # half A, half B: two ranks
    assert set(edge[:, 0]) | set(edge[:, 2]) == {id_a, id_b}
    assert np.allclose(edge[:, 1] + edge[:, 3], 1.0) and np.all(edge[:, 1] >= edge[:, 3])
    assert np.all(np.abs(edge[:, 1] - 0.5) < 4 * 0.5 / np.sqrt(64) + 1e-6)
    assert np.all(ob[:, 7] == 0) and np.all(img["CryptoObject01"] == 0)
    mat = img["CryptoMaterial00"]
    assert np.all(mat[:, :3, 0] == cm.ids(["mat_a"])[0]) and np.all(mat[:, 4:7, 0] == cm.ids(["mat_b"])[0])
    asset = img["CryptoAsset00"]                                # both objects are the asset 'Rig'
    assert np.all(asset[:, :7, 0] == cm.ids(["Rig"])[0]) and np.allclose(asset[:, :7, 1], 1.0)
    assert np.all(asset[:, 7] == 0)
    # no material: Cycles' default shader's name
    scene = _two_quads(cryptomatte=('CryptoMaterial',), cryptomatte_levels=2)
    scene.geometry.material[:] = 0
    img = render(scene).film.cryptomatte_images()
    assert sorted(img) == ["CryptoMaterial00"]
    assert np.all(img["CryptoMaterial00"][:, :7, 0] == cm.ids([cm.DEFAULT_MATERIAL])[0])


@pytest.mark.parametrize('threshold', [0.5])
def test_coverage_through_a_transparent_sheet(threshold):
    """A sheet of alpha 0.6 over a floor: the sheet covers 0.6 of each pixel, the floor what
    passes, 0.4 (Cycles: throughput x (1 - transparency) at each surface)."""
    sheet = material('sheet', (0.3,) * 3, transparency=np.full(3, 0.4, np.float32))
    scene = sheet_scene(sheet, floor=True, samples=256, cryptomatte=('CryptoMaterial',),
                        pass_alpha_threshold=threshold)
    film = render(scene).film
    img = film.cryptomatte_images()["CryptoMaterial00"]
    names = cm.layer_names(scene, 'CryptoMaterial')
    sheet_id = cm.ids([names[[m.name for m in scene.materials].index('sheet')]])[0]
    assert np.all(img[..., 0] == sheet_id) and np.allclose(img[..., 1], 0.6, rtol=1e-5)
    n = img[..., 3].size * 256
    assert img[..., 3].mean() == pytest.approx(0.4, abs=4 * 0.5 / np.sqrt(n))
