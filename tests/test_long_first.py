"""The long-tests-first order of tests/conftest.py: under xdist's worksteal every worker's first
share of the collection starts with its round-robin deal of the long (`long`, `stress`) tests,
the other tests keep their order, and nothing is lost or repeated."""
from types import SimpleNamespace

from tests import conftest


class Item:
    def __init__(self, name, *markers):
        self.name, self.markers = name, markers

    def get_closest_marker(self, name):
        return name if name in self.markers else None

    def __repr__(self):
        return self.name


def config(workers, dist="worksteal"):
    options = {"dist": dist}
    return SimpleNamespace(workerinput={"workercount": workers},
                           getoption=lambda name, default=None: options.get(name, default))


def collection():
    return [Item(f"s{i}") for i in range(7)] + [Item("l0", "long"), Item("l1", "stress"),
                                                Item("s7"), Item("l2", "long")]


def names(items):
    return [i.name for i in items]


def test_each_workers_first_share_starts_with_its_long_tests():
    items = collection()
    conftest.pytest_collection_modifyitems(config(2), items)
    # worksteal sends the first 11 // 2 = 5 items to one worker and the other 6 to the other
    assert names(items[:5]) == ["l0", "l2", "s0", "s1", "s2"]
    assert names(items[5:]) == ["l1", "s3", "s4", "s5", "s6", "s7"]


def test_three_workers_get_one_long_test_each():
    items = collection()
    conftest.pytest_collection_modifyitems(config(3), items)
    # shares of 11 // 3 = 3, then 8 // 2 = 4 and 4 items
    assert names(items) == ["l0", "s0", "s1", "l1", "s2", "s3", "s4", "l2", "s5", "s6", "s7"]


def test_more_long_tests_than_a_share_holds_go_first_in_order():
    items = [Item("s0"), Item("l0", "long"), Item("l1", "long"), Item("l2", "long"), Item("l3", "long")]
    conftest.pytest_collection_modifyitems(config(3), items)     # shares of 1, 2 and 2 items
    assert names(items) == ["l0", "l1", "l2", "l3", "s0"]


def test_one_process_or_another_scheduler_keeps_the_collection_order():
    for cfg in (SimpleNamespace(getoption=lambda name, default=None: "no"), config(1), config(2, "load")):
        items = collection()
        conftest.pytest_collection_modifyitems(cfg, items)
        assert names(items) == names(collection())
