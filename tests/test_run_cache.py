"""The server's run cache is bounded by what its runs really hold: the arrays of the run and of
the drawings kept with it (a drawing is 2-10 times its run), and what goes to disk is the run
alone."""
from __future__ import annotations

from theoria.app.worker import RunCache, RunStore, drawing_of, nbytes
from theoria.scenarios import get


def _run(name: str, **given):
    spec = get(name)
    run = spec.simulate_fn(spec.resolve(given))
    run.spec = spec
    return spec, run


def test_a_drawing_kept_with_a_cached_run_is_counted_and_pushes_out_the_oldest():
    spec, a = _run("free-tumble")
    _, b = _run("free-tumble", duration=10.0)
    run_bytes = nbytes(a)
    cache = RunCache(max_bytes=1e12)
    cache.put("a", a, 0.1)
    assert cache.size_bytes == run_bytes
    d = drawing_of(spec, a)
    assert nbytes(d) > run_bytes  # the drawing is the larger part
    assert cache.size_bytes == run_bytes + nbytes(d)
    assert drawing_of(spec, a) is d and cache.size_bytes == run_bytes + nbytes(d)  # kept, not counted twice

    # room for four runs with their drawings, less one byte: drawing the fourth run's scene
    # pushes out the least recently used run
    runs = [_run("free-tumble")[1] for _ in range(4)]
    cache = RunCache(max_bytes=4 * (run_bytes + nbytes(d)) - 1)
    for k, r in enumerate(runs):
        cache.put(str(k), r, 0.1)
    for r in runs[:3]:
        drawing_of(spec, r)
    assert all(cache.get(str(k)) is not None for k in range(4))
    cache.get("0")  # used again: the second run is now the least recently used
    drawing_of(spec, runs[3])
    assert cache.get("1") is None and all(cache.get(k) is not None for k in ("0", "2", "3"))
    assert cache.size_bytes <= cache.max_bytes


def test_a_stored_run_carries_neither_its_drawings_nor_the_cache(tmp_path):
    spec, run = _run("free-tumble")
    cache = RunCache()
    cache.put("k", run, 0.1)
    drawing_of(spec, run)
    store = RunStore(tmp_path)
    store.put("free-tumble:abc", run, 0.1)
    back, seconds = store.get("free-tumble:abc")
    assert seconds == 0.1 and not [k for k in vars(back) if k.startswith("_theoria_")]
    assert (back.trajectory.t == run.trajectory.t).all()
    assert "_theoria_drawings" in vars(run)  # the server's own copy keeps its drawings


def _arrays_reached(obj, depth=0) -> int:
    """Every numpy array reached from `obj` through dicts, lists and tuples (their first 10,000
    items) and dataclass fields (not `spec`), at most six levels down: what the run cache counts."""
    import dataclasses

    import numpy as np

    if depth > 6:
        return 0
    if isinstance(obj, np.ndarray):
        return obj.nbytes
    if isinstance(obj, dict):
        return sum(_arrays_reached(v, depth + 1) for v in obj.values())
    if isinstance(obj, (list, tuple)):
        return sum(_arrays_reached(v, depth + 1) for v in obj[:10000])
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        names = {f.name for f in dataclasses.fields(obj)}
        kept = {k: v for k, v in vars(obj).items()
                if k not in names and k not in ("_theoria_drawings", "_theoria_cache", "spec")}
        return (sum(_arrays_reached(getattr(obj, f), depth + 1) for f in names if f != "spec")
                + sum(_arrays_reached(v, depth + 1) for v in kept.values()))
    return 0


def test_the_cache_counts_what_a_trajectory_computed_and_kept_after_it_came():
    """A Trajectory computes ω, L in space, the energy and the axes and keeps them beside its
    fields: the cache counted only the fields, 55.7 MB of the 90.8 MB a long earth-long-view held,
    so the "1 GB" cache held 1.6 GB and the server grew past what the classroom page promises.
    Everything a run keeps is counted, and measured again when a drawing is kept with it."""
    from theoria.app.worker import RunCache

    spec = get("middle-axis-flip")
    run = spec.simulate()
    cache = RunCache(max_bytes=1e9)
    cache.put("k", run, 0.1)
    before = cache.size_bytes
    drawing = drawing_of(spec, run)  # asks the trajectory for its derived arrays, and keeps itself with the run
    tr = run.trajectory
    fields = sum(nbytes(getattr(tr, f)) for f in tr.__dataclass_fields__)
    derived = sum(v.nbytes for k, v in vars(tr).items() if k not in tr.__dataclass_fields__ and hasattr(v, "nbytes"))
    assert derived > 0 and nbytes(tr) == fields + derived
    assert before == nbytes(run) and cache.size_bytes == nbytes(run) + nbytes(drawing) > before


def test_the_cache_counts_every_array_of_runs_and_drawings():
    """The cache's size of a run and of its drawing (walked quickly: leaves without a call) is the
    bytes of every array reached from it, for scenes whose drawings hold per-frame text, paths,
    meshes and sections."""
    for name, given in [("hyperion", {"n_starts": 6, "n_orbits": 20, "probe_orbits": 2}),
                        ("libration-eccentric", {"orbits": 3}), ("middle-axis-flip", {}), ("moon", {"years": 1})]:
        spec = get(name)
        run = spec.simulate(given)
        drawing = drawing_of(spec, run)
        for obj in (run.trajectory, run.extras, run.plot_series, drawing):
            assert nbytes(obj) == _arrays_reached(obj), (name, type(obj).__name__)
        assert nbytes(drawing) > 0 and nbytes(run.trajectory) > 0, name


def test_warm_marks_belong_to_the_install_whose_numba_cache_they_describe(tmp_path, monkeypatch):
    """Without NUMBA_CACHE_DIR numba keeps compiled code beside the installed sources: a second
    virtual environment with the same code found the first one's marks, took itself for warm and
    compiled on the serving path (a link to libration-circular: 19 s to its first scene)."""
    from theoria.app import worker

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("THEORIA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(worker, "install_key", lambda: "first-venv")
    first = worker.WarmMarks()
    first.add("libration-circular")
    assert "libration-circular" in worker.WarmMarks()
    monkeypatch.setattr(worker, "install_key", lambda: "second-venv")
    assert "libration-circular" not in worker.WarmMarks()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))  # one cache for every install: one set of marks
    worker.WarmMarks().add("moon")
    monkeypatch.setattr(worker, "install_key", lambda: "first-venv")
    assert "moon" in worker.WarmMarks()


def test_a_drawing_is_kept_under_the_view_it_was_drawn_with():
    """A browser's thread may change its view (the exaggeration, an option, presenter size)
    while the server draws with it: the drawing kept must be the one its key names."""
    from types import SimpleNamespace

    from theoria.scenarios.drawing import View

    shown = View(exaggerate=1.0, options={"trail": True})

    def drawing(run, view):
        shown.exaggerate, shown.options["trail"] = 5.0, False  # the other thread, meanwhile
        return (view.exaggerate, view.option("trail"))

    spec = SimpleNamespace(name="probe", drawing=drawing)
    run = SimpleNamespace()
    assert drawing_of(spec, run, shown) == (1.0, True)
    assert drawing_of(spec, run, View(exaggerate=1.0, options={"trail": True})) == (1.0, True)
