"""lights/linking.py says when Blender's other light linking limit is passed: it numbers each
distinct combination of linking collections an object is in (depsgraph_light_linking.cc,
LinkingData::end_build), 63 besides the unlinked set, in the order of a Map keyed by object
pointer, and leaves the objects of the combinations past that unlinked. Which ones follows
memory order, so Cycles' image changes between runs (64 lamps each lighting plane A and a plane
of its own, 65 combinations: Cycles lit A with all 64 lamps, or, about 1 run in 30-65, A and B
with one); DACRT keeps every link and had said nothing."""
from addon.lights.linking import LightLinking, combinations, reached

INC = 'light linking receiver'


def _warnings(links, objects, kind=INC):
    messages = []
    LightLinking(links, objects, messages, unlinked=False, kind=kind)
    return [text for _, text in messages if "combinations" in text]


def _own_plane(n, shared=("A",)):
    """n lamps, lamp i lighting `shared` and a plane Di of its own."""
    return {f"L{i:02d}": (frozenset({*shared, f"D{i}"}), frozenset()) for i in range(n)}


def _objects(n):
    return ["A", "B"] + [f"D{i}" for i in range(n)]


def test_a_shared_plane_and_64_planes_of_their_own_are_65_combinations():
    assert combinations(list(_own_plane(64).values())) == 65
    text = _warnings(_own_plane(64), _objects(64))
    assert len(text) == 1 and "objects in 65 different combinations of light linking receiver collections, " \
        "past Blender's 63: it leaves the objects of 2 unlinked, picked by memory order" in text[0], text


def test_63_combinations_are_said_nothing_of_64_are():
    assert combinations(list(_own_plane(63, shared=()).values())) == 63
    assert not _warnings(_own_plane(63, shared=()), _objects(63))
    assert _warnings(_own_plane(64, shared=()), _objects(64))
    assert not _warnings(_own_plane(62), _objects(62))          # A's and 62 planes'


def test_objects_with_the_same_combination_share_it():
    """64 lamps lighting A and the planes of the bits of their index: 7 combinations (A's, and
    each bit plane's), the light sets still 64 and each object's mask its lamps'."""
    links = {f"L{i:02d}": (frozenset({"A"} | {f"D{j}" for j in range(6) if i >> j & 1}), frozenset())
             for i in range(64)}
    messages = []
    link = LightLinking(links, _objects(6), messages, unlinked=False)
    assert not messages and combinations(list(links.values())) == 7
    for i in range(64):
        assert list(reached(link.object_mask, link.emitter_set(f"L{i:02d}"))) == \
            [True, False] + [bool(i >> j & 1) for j in range(6)]


def test_an_exclusion_makes_its_own_combination():
    """An object's light set is the pair (collections including it, collections excluding it):
    excluding B from one lamp and including it in none gives B a combination of its own."""
    links = {"L0": (frozenset({"A"}), frozenset()), "L1": (frozenset(), frozenset({"B"})),
             "L2": (frozenset({"A"}), frozenset({"B"}))}
    assert combinations(list(dict.fromkeys(links.values()))) == 2      # A: {0, 2}; B: excluded by {1, 2}


def test_blocker_collections_alike():
    text = _warnings(_own_plane(64), _objects(64), kind='shadow linking blocker')
    assert len(text) == 1 and "combinations of shadow linking blocker collections" in text[0], text


def test_past_64_collections_only_the_first_64_link_objects():
    """Blender links no objects for the collections past its 64 (their lamps light everything):
    70 lamps with planes of their own count A's and the first 64 planes', not 71."""
    text = _warnings(_own_plane(70), _objects(70))
    assert len(text) == 1 and "objects in 65 different combinations" in text[0], text
