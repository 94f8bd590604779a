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
    """A worker's config as xdist makes it: its own dist option is "no"; the controller's
    command line (where --dist was given) arrives as workerinput["mainargv"]."""
    argv = ["pytest", "-n", str(workers)] + (["--dist", dist] if dist else [])
    return SimpleNamespace(workerinput={"workercount": workers, "mainargv": argv},
                           getoption=lambda name, default=None: "no" if name == "dist" else default)


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
    for cfg in (SimpleNamespace(getoption=lambda name, default=None: "no"), config(1), config(2, "load"),
                config(2, None)):
        items = collection()
        conftest.pytest_collection_modifyitems(cfg, items)
        assert names(items) == names(collection())


def test_the_dist_mode_is_read_from_the_controllers_command_line():
    assert conftest._controller_dist(["pytest", "-n", "2", "--dist", "worksteal", "tests"]) == "worksteal"
    assert conftest._controller_dist(["pytest", "--dist=worksteal"]) == "worksteal"
    assert conftest._controller_dist(["pytest", "-n", "2"]) == "load"


def test_a_real_two_worker_run_starts_each_worker_on_a_long_test(tmp_path):
    """Through xdist itself (its workers' config says dist "no"): the first test each worker runs
    is a long one."""
    import subprocess
    import sys
    (tmp_path / "conftest.py").write_text("from tests.conftest import pytest_collection_modifyitems, "
                                          "pytest_configure, pytest_addoption\n")
    (tmp_path / "test_order.py").write_text(
        "import os, pytest\n"
        + "".join(f"def test_s{i}():\n    pass\n" for i in range(8))
        + "".join(f"@pytest.mark.long\ndef test_l{i}():\n    pass\n" for i in range(2)))
    root = str(__import__("pathlib").Path(__file__).resolve().parents[1])
    out = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-n", "2", "--dist",
                          "worksteal", "-v", f"--rootdir={tmp_path}", str(tmp_path)],
                         capture_output=True, text=True, cwd=tmp_path,
                         env={**__import__("os").environ, "PYTHONPATH": root})
    assert out.returncode == 0, out.stdout + out.stderr
    firsts = {}
    for line in out.stdout.splitlines():                 # "[gw0] [ 10%] PASSED test_order.py::test_l0"
        if line.startswith("[gw") and "PASSED" in line:
            firsts.setdefault(line.split("]")[0], line.rsplit("::", 1)[1].strip())
    assert sorted(firsts.values()) == ["test_l0", "test_l1"], out.stdout
