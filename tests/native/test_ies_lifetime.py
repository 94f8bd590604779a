"""IES tables live as long as the handles (dacrt.lamps.IesProfile) that name them (native/cpp/ies.h):
the last handle's release frees the table and its slot, identical tables share a slot counted,
so a viewport editing a profile or an animation cycling them never fills the registry
(IES_MAX_TABLES bounds only the tables alive at once), and a record naming a released id is
refused rather than read."""
import gc

import numpy as np
import pytest

import dacrt
from addon import scenedata as sd
from addon.lights import lamp_records, make_lamp

F32 = np.float32
H = np.radians([0.0, 90.0, 180.0, 270.0, 360.0]).astype(F32)
V = np.radians([0.0, 45.0, 90.0, 135.0, 180.0]).astype(F32)


def table(k):
    """A distinct (H, V) table per k."""
    rng = np.random.default_rng(k)
    return (rng.random((len(H), len(V))) * 100 + k).astype(F32)


def register(k):
    return dacrt.lamps.ies_register(H, V, table(k))


def test_last_handle_frees_the_table_and_its_slot():
    gc.collect()
    base = dacrt.lamps.ies_live()
    a = register(1)
    assert isinstance(a, dacrt.lamps.IesProfile) and int(a) == a.id >= 1
    assert dacrt.lamps.ies_live() == base + 1
    old = a.id
    del a
    assert dacrt.lamps.ies_live() == base
    with pytest.raises(ValueError, match='not live'):
        dacrt.lamps.ies_lookup(old, [0.5], [0.5])
    b = register(2)         # the freed slot is reused, under a new id
    assert dacrt.lamps.ies_live() == base + 1 and b.id != old
    del b
    assert dacrt.lamps.ies_live() == base


def test_identical_tables_share_a_slot_until_both_go():
    gc.collect()
    base = dacrt.lamps.ies_live()
    a, b = register(3), register(3)
    assert a.id == b.id and dacrt.lamps.ies_live() == base + 1
    h = np.linspace(0, 2 * np.pi, 50, dtype=F32)
    v = np.linspace(0, np.pi, 50, dtype=F32)
    want = dacrt.lamps.ies_lookup(a, h, v)
    del a                   # b still holds it: the table is still there, unchanged
    assert dacrt.lamps.ies_live() == base + 1
    np.testing.assert_array_equal(dacrt.lamps.ies_lookup(b, h, v), want)
    np.testing.assert_array_equal(dacrt.lamps.ies_lookup(b.id, h, v), want)
    del b
    assert dacrt.lamps.ies_live() == base


def test_many_more_profiles_than_slots_one_after_another():
    gc.collect()
    base = dacrt.lamps.ies_live()
    I = table(4)
    for k in range(10 * dacrt.lamps.IES_MAX_TABLES):
        I[0, 0] = k          # distinct each time; each dropped before the next
        p = dacrt.lamps.ies_register(H, V, I)
        assert dacrt.lamps.ies_live() == base + 1
        del p
    assert dacrt.lamps.ies_live() == base


def test_the_bound_is_on_tables_alive_at_once():
    gc.collect()
    base = dacrt.lamps.ies_live()
    I = table(5)
    held = []
    for k in range(dacrt.lamps.IES_MAX_TABLES - base):
        I[0, 0] = k
        held.append(dacrt.lamps.ies_register(H, V, I))
    I[0, 0] = -1
    with pytest.raises(ValueError, match='too many distinct IES profiles alive'):
        dacrt.lamps.ies_register(H, V, I)
    held.pop()
    dacrt.lamps.ies_register(H, V, I)       # one slot freed: one more fits
    held.clear()
    assert dacrt.lamps.ies_live() == base


def test_lookups_through_a_live_handle_are_unchanged():
    p = register(6)
    h = np.radians(np.arange(0, 360, 7.5)).astype(F32)
    v = np.radians(np.arange(0, 180, 7.5)).astype(F32)
    hh, vv = [x.ravel() for x in np.meshgrid(h, v)]
    first = dacrt.lamps.ies_lookup(p, hh, vv)
    churn = [register(100 + k) for k in range(50)]      # others registered and released meanwhile
    del churn
    np.testing.assert_array_equal(dacrt.lamps.ies_lookup(p, hh, vv), first)
    # at the table's own angles the lookup is the table
    np.testing.assert_allclose(dacrt.lamps.ies_lookup(p, np.repeat(H[:-1], len(V) - 1), np.tile(V[:-1], len(H) - 1)),
                               table(6)[:-1, :-1].ravel(), rtol=1e-5)


def test_records_naming_a_freed_id_are_refused():
    class Profile:       # addon/lights/ies.py IESProfile's fields
        h_angles, v_angles, intensity = H, V, table(7)

    lamp = make_lamp(sd.Light('POINT', np.asarray((40.0, 30.0, 20.0), F32), np.eye(4), ies=Profile()))
    recs = lamp_records([lamp])
    args = (np.zeros(1, np.int32), np.ones((3, 1), F32), np.zeros(1, F32), np.zeros(1, F32))
    dacrt.lamps.lamp_sample(recs, *args)    # the lamp holds its table: the record is read
    del lamp
    gc.collect()
    with pytest.raises(ValueError, match='not a live IES profile id'):
        dacrt.lamps.lamp_sample(recs, *args)
