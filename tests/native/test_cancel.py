"""Cancelling a trace part-way (Scene.intersect / occluded `cancel`): the callable is asked on
the calling thread while the rays are traced, a true answer stops every thread and raises
dacrt.Cancelled, a false one changes no hit, its exceptions propagate, and a scene that kept its
top levels (keep_top) gives exact results after a cancelled call, on every ISA and thread count."""

import dacrt
import numpy as np
import pytest

from . import scenes

ISAS = dacrt.supported_isas()


@pytest.fixture(scope="module")
def case():
    rng = np.random.default_rng(59)
    v, t = scenes.random_soup(rng, 20000, spread=1.0, size=0.05)
    # enough rays that the calling thread's own share of the work asks the callable far more
    # than 40 times even when a loaded machine deschedules it (with 64K rays, CI under load 5
    # once saw an occluded call on 2 threads finish before its 40th question)
    n = 1 << 18
    org = rng.uniform(-1.2, 1.2, (n, 3)).astype(np.float32)
    d = rng.normal(size=(n, 3)).astype(np.float32)
    return v, t, org, d


def rays_of(case):
    _, _, org, d = case
    return dacrt.make_rays(org, d)


@pytest.fixture
def every_step(monkeypatch):
    monkeypatch.setattr(dacrt, "CANCEL_POLL_SECONDS", 0.0)   # ask at every recursion step


class Countdown:
    """Says stop at its k-th call; counts the calls and the threads they came from."""

    def __init__(self, k):
        import threading
        self.k, self.calls, self.threads, self._get = k, 0, set(), threading.get_ident

    def __call__(self):
        self.calls += 1
        self.threads.add(self._get())
        return self.calls >= self.k


@pytest.mark.parametrize("isa", ISAS)
@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("query", ["intersect", "occluded"])
def test_a_true_answer_stops_the_call_and_the_kept_top_stays_exact(monkeypatch, every_step, case, isa, threads, query):
    import threading
    monkeypatch.setenv("DACRT_ISA", isa)
    v, t, _, _ = case
    fresh = getattr(dacrt.Scene(v, t), query)(rays_of(case), threads=threads)
    scene = dacrt.Scene(v, t, keep_top=True)
    for k in (1, 3, 40):                 # stop at the first step, early, and deep in the tree
        stop = Countdown(k)
        with pytest.raises(dacrt.Cancelled):
            getattr(scene, query)(rays_of(case), threads=threads, cancel=stop)
        assert stop.calls == k                       # not asked again once it said stop
        assert stop.threads == {threading.get_ident()}   # only ever on the calling thread
        # the kept top's splits made before the stop are complete: later calls stay exact
        assert np.array_equal(getattr(scene, query)(rays_of(case), threads=threads), fresh)


@pytest.mark.parametrize("isa", ISAS)
def test_a_false_answer_changes_no_hit(monkeypatch, every_step, case, isa):
    monkeypatch.setenv("DACRT_ISA", isa)
    v, t, _, _ = case
    scene = dacrt.Scene(v, t, keep_top=True)
    for threads in (1, 2):
        go = Countdown(10 ** 12)
        hits = scene.intersect(rays_of(case), threads=threads, cancel=go)
        assert go.calls > 10                          # asked at every step, as requested
        assert np.array_equal(hits, dacrt.Scene(v, t).intersect(rays_of(case), threads=threads))
        assert (hits["prim"] >= 0).sum() > len(hits) // 10
        occ = scene.occluded(rays_of(case), threads=threads, cancel=lambda: 0)   # falsy, not False
        assert np.array_equal(occ, dacrt.Scene(v, t).occluded(rays_of(case), threads=threads))


def test_the_default_interval_asks_rarely(monkeypatch, case):
    """At CANCEL_POLL_SECONDS (0.05 s) a trace of a fraction of a second asks a few times at
    most, not once per step (a renderer's test_break is not free)."""
    v, t, _, _ = case
    rare, often = Countdown(10 ** 12), Countdown(10 ** 12)
    dacrt.Scene(v, t).intersect(rays_of(case), threads=1, cancel=rare)
    monkeypatch.setattr(dacrt, "CANCEL_POLL_SECONDS", 0.0)
    dacrt.Scene(v, t).intersect(rays_of(case), threads=1, cancel=often)
    assert often.calls > 1000 and rare.calls <= often.calls // 100


def test_truthiness_and_exceptions_of_the_callable(every_step, case):
    v, t, _, _ = case
    scene = dacrt.Scene(v, t, keep_top=True)
    with pytest.raises(dacrt.Cancelled, match="cancelled"):
        scene.intersect(rays_of(case), cancel=lambda: np.bool_(True))

    def broken():
        raise KeyError("from the callable")
    with pytest.raises(KeyError, match="from the callable"):
        scene.intersect(rays_of(case), threads=2, cancel=broken)

    class Undecided:
        def __bool__(self):
            raise ValueError("no truth value")
    with pytest.raises(ValueError, match="no truth value"):
        scene.occluded(rays_of(case), cancel=lambda: Undecided())
    with pytest.raises(TypeError, match="cancel must be a callable"):
        scene.intersect(rays_of(case), cancel=True)
    assert np.array_equal(scene.intersect(rays_of(case)), dacrt.Scene(v, t).intersect(rays_of(case)))


def test_cancelled_is_an_exception_of_the_package():
    assert issubclass(dacrt.Cancelled, Exception)
    assert "Cancelled" in dacrt.__all__ and dacrt.CANCEL_POLL_SECONDS == pytest.approx(0.05)
