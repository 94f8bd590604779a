"""lights/linking.py's limit on light sets, as Cycles': 64 linking collections. Where every
emitter is linked, bit 0 is a linked set's too and all 64 fit; with an unlinked emitter (or a
lighting world) set 0 is everyone's and 63 fit, said so; past 64 the emitters beyond light every
object, as in Cycles (it had kept 63 in every case: the 64th lit every object)."""
from addon.lights.linking import LightLinking, reached


def _links(n):
    """n lamps, lamp i lighting plane A and the planes Dj of the bits j of i: n distinct sets, and
    8 combinations of collections per object, well within Blender's 63 (test_linking_combinations)."""
    return {f"L{i:02d}": (frozenset({"A"} | {f"D{j}" for j in range(7) if i >> j & 1}), frozenset())
            for i in range(n)}


def _objects(n):
    return ["A", "B"] + [f"D{j}" for j in range(7)]


def test_64_sets_fit_where_every_emitter_is_linked():
    messages = []
    link = LightLinking(_links(64), _objects(64), messages, unlinked=False)
    assert not messages, messages
    sets = [link.emitter_set(f"L{i:02d}") for i in range(64)]
    assert sorted(sets) == list(range(64)) and link.everyone is None
    for i, s in enumerate(sets):                  # each lights A and the D of its bits, never B
        assert list(reached(link.object_mask, s)) == [True, False] + [bool(i >> j & 1) for j in range(7)]


def test_63_sets_fit_beside_an_unlinked_emitter():
    messages = []
    link = LightLinking(_links(64), _objects(64), messages, unlinked=True)
    assert link.everyone == 0 and reached(link.object_mask, 0).all()
    assert link.emitter_set("L63") == 0 and sorted(link.emitter_set(f"L{i:02d}") for i in range(63)) == \
        list(range(1, 64))
    assert len(messages) == 1 and "only 63 sets fit" in messages[0][1] and "L63 light every object" in \
        messages[0][1], messages


def test_past_64_sets_the_rest_light_every_object():
    messages = []
    link = LightLinking(_links(70), _objects(70), messages, unlinked=False, kind='light linking receiver')
    text = messages[0][1]
    assert "more than 64 different light linking receiver sets (Cycles' limit)" in text, text
    assert "L64, L65, L66, L67, L68, L69 light every object, as in Cycles" in text, text
    assert "so do L63 here" in text, text           # set 0 is theirs: 63 fit
    assert [link.emitter_set(f"L{i}") for i in (62, 63, 69)] == [63, 0, 0]
