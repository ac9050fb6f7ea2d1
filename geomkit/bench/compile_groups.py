"""Compile time per kernel group, and per compiled function.

Run in a fresh interpreter with an empty cache::

    NUMBA_CACHE_DIR=$(mktemp -d) python -m geomkit.bench.compile_groups
    NUMBA_CACHE_DIR=$(mktemp -d) python -m geomkit.bench.compile_groups distance,motion
    NUMBA_CACHE_DIR=$(mktemp -d) python -m geomkit.bench.compile_groups --profile demo
    GEOMKIT_COMPILE_LOG=/tmp/log NUMBA_CACHE_DIR=$(mktemp -d) python -m geomkit demo
    python -m geomkit.bench.compile_groups --log /tmp/log

Without ``--profile``: the CPU and wall time of the first and second call of each group
(the difference is the compile time; later groups reuse what earlier ones compiled).

With ``--profile``: numba's ``numba:compile`` and ``numba:run_pass`` events are
recorded (:class:`CompileProfile`) and a table is printed per compiled function
(module, number of compiles = signatures, *exclusive* CPU = its own typing, lowering
and code generation, *inclusive* CPU = with the callees compiled while typing it),
per kernel module, per group step and per compiler pass.  The group ``demo`` runs
:func:`geomkit.jobs.demo.run_demo` without its background helper, so every kernel the demo
needs is compiled (and attributed) in this process.

With ``--log FILE``: summarise a compile log written by any geomkit run with
``GEOMKIT_COMPILE_LOG=FILE`` (every process appends to it, the demo's background
compile helper included): per process compiles and CPU, and the functions compiled
in more than one process.  See docs/compile.md.
"""

from __future__ import annotations

import collections
import time


class CompileProfile:
    """Records numba compilations: per function (exclusive / inclusive CPU seconds,
    count) and per compiler pass (exclusive CPU).  ``start()`` registers the
    listeners, ``stop()`` removes them; ``mark(name)`` attributes what follows to a
    step (a group).  CPU is ``time.process_time`` (the whole process; compilation
    holds numba's compiler lock, so other threads add little)."""

    def __init__(self):
        from numba.core import event
        self._event = event
        self.funcs = collections.defaultdict(lambda: [0, 0.0, 0.0])  # n, incl, excl
        self.passes = collections.defaultdict(float)
        self.steps = collections.defaultdict(float)  # step -> exclusive compile CPU
        self.step = "-"
        self._fstack, self._pstack = [], []
        prof = self

        class _Funcs(event.Listener):
            def on_start(self, ev):
                d = ev.data["dispatcher"].py_func
                prof._fstack.append((f"{d.__module__}.{d.__qualname__}",
                                     time.process_time(), [0.0]))

            def on_end(self, ev):
                name, t0, kids = prof._fstack.pop()
                dt = time.process_time() - t0
                r = prof.funcs[name]
                r[0] += 1
                r[1] += dt
                r[2] += dt - kids[0]
                prof.steps[prof.step] += dt - kids[0]
                if prof._fstack:
                    prof._fstack[-1][2][0] += dt

        class _Passes(event.Listener):
            def on_start(self, ev):
                name = ev.data["name"].split(" [")[0]  # "native_lowering [func]"
                prof._pstack.append((name, time.process_time(), [0.0]))

            def on_end(self, ev):
                name, t0, kids = prof._pstack.pop()
                dt = time.process_time() - t0
                prof.passes[name] += dt - kids[0]
                if prof._pstack:
                    prof._pstack[-1][2][0] += dt

        self._listeners = [("numba:compile", _Funcs()), ("numba:run_pass", _Passes())]

    def start(self):
        for kind, lsn in self._listeners:
            self._event.register(kind, lsn)
        return self

    def stop(self):
        for kind, lsn in self._listeners:
            self._event.unregister(kind, lsn)

    def mark(self, step):
        self.step = step

    def report(self, top=40, file=None):
        import sys
        out = file or sys.stdout
        tot = sum(r[2] for r in self.funcs.values())
        print(f"\ncompile CPU, all functions (exclusive sum): {tot:.1f} s in "
              f"{sum(r[0] for r in self.funcs.values())} compiles of "
              f"{len(self.funcs)} functions", file=out)
        print("\nper step (group):", file=out)
        for s, t in self.steps.items():
            print(f"  {s:24s} {t:7.1f} s", file=out)
        mods = collections.defaultdict(lambda: [0, 0.0])
        for name, (n, _, ex) in self.funcs.items():
            m = mods[name.rsplit(".", 1)[0] if "<locals>" not in name else name]
            m[0] += n
            m[1] += ex
        print("\nper module (exclusive CPU, compiles):", file=out)
        for m, (n, ex) in sorted(mods.items(), key=lambda kv: -kv[1][1]):
            print(f"  {ex:7.2f} s  x{n:<3d} {m}", file=out)
        print(f"\ntop {top} functions (exclusive / inclusive CPU, compiles):", file=out)
        for name, (n, inc, ex) in sorted(self.funcs.items(), key=lambda kv: -kv[1][2])[:top]:
            print(f"  {ex:7.2f} {inc:7.2f}  x{n:<2d} {name}", file=out)
        print("\ncompiler passes (exclusive CPU):", file=out)
        for name, t in sorted(self.passes.items(), key=lambda kv: -kv[1])[:15]:
            print(f"  {t:7.2f} s  {name}", file=out)


def read_log(path, file=None):
    """Summarise a ``GEOMKIT_COMPILE_LOG`` file (see :mod:`geomkit._kernels.numba_ext.policy`):
    per process the compiles, exclusive CPU and the span of its compilations; the
    functions compiled in more than one process (compiled twice: wasted CPU)."""
    import sys
    out = file or sys.stdout
    rows = []
    with open(path) as fh:
        for line in fh:
            pid, name, w0, w1, ex = line.rstrip("\n").split("\t")
            rows.append((pid, name, float(w0), float(w1), float(ex)))
    if not rows:
        print("no compilations logged", file=out)
        return {}
    t0 = min(r[2] for r in rows)
    procs = collections.defaultdict(list)
    for r in rows:
        procs[r[0]].append(r)
    for pid, rs in procs.items():
        print(f"process {pid}: {len(rs)} compiles, {sum(r[4] for r in rs):.1f} s CPU, "
              f"from {min(r[2] for r in rs) - t0:.1f} s to {max(r[3] for r in rs) - t0:.1f} s",
              file=out)
    by = collections.defaultdict(lambda: collections.defaultdict(float))
    for pid, name, _, _, ex in rows:
        by[name][pid] += ex
    dup = {n: d for n, d in by.items() if len(d) > 1}
    waste = sum(sum(d.values()) - max(d.values()) for d in dup.values())
    print(f"compiled in more than one process: {len(dup)} functions, "
          f"{waste:.1f} s CPU compiled twice", file=out)
    for n, d in sorted(dup.items(), key=lambda kv: -sum(kv[1].values()))[:20]:
        print(f"  {sum(d.values()):6.2f} s  {n}", file=out)
    return {"processes": len(procs), "duplicates": len(dup), "duplicate_cpu": waste,
            "cpu": sum(r[4] for r in rows)}


def _groups():
    import numpy as np

    import geomkit
    from geomkit import samples
    surf = samples.load("freeform_1")[0]
    plate = samples.load("plate_with_hole")[0]

    def g_tess():
        geomkit.tessellate(surf, 1e-2)

    def g_trim():
        geomkit.classify_uv(plate, np.array([[0.5, 0.5], [0.1, 0.2]]))

    def g_proj():
        geomkit.project_points(plate, np.array([[50, 50, 3.0], [10, 10, 1.0]]))

    def g_sec():
        geomkit.plane_section(surf, np.array([1.0, 0, 0, -50.0]), 1e-4)

    def g_dist():
        a, b = samples.load("sphere_pair")
        geomkit.surface_distance(a, b, tol=1e-6)

    def g_coll():
        m = geomkit.tessellate(samples.load("sphere")[0], 1e-1)
        A = geomkit.Body(m)
        T = np.eye(4)
        T[0, 3] = 5.0
        geomkit.collide(A, np.eye(4), A, T)
        geomkit.min_distance(A, np.eye(4), A, T)

    def g_motion():
        m = geomkit.tessellate(samples.load("sphere")[0], 1e-1)
        A = geomkit.Body(m)
        T = np.eye(4)
        T[0, 3] = 30.0
        geomkit.first_contact(A, np.eye(4), np.zeros(3), A, T, np.array([-1.0, 0, 0]), 30.0)

    def g_demo():
        import tempfile

        from geomkit.jobs.demo import run_demo
        with tempfile.TemporaryDirectory() as d:
            run_demo(d, warm_up=False, progress=_demo_progress)

    return dict(tessellate=g_tess, trim=g_trim, projection=g_proj, section=g_sec,
                distance=g_dist, collision=g_coll, motion=g_motion, demo=g_demo)


_PROFILE = None


def _demo_progress(step, summary, seconds):
    if _PROFILE is not None and summary is None:
        _PROFILE.mark(f"demo:{step}")


def main(argv=None):
    import sys
    global _PROFILE
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] == "--log":
        read_log(args[1])
        return
    profile = "--profile" in args
    args = [a for a in args if a != "--profile"]
    order = args[0].split(",") if args else \
        ["tessellate", "trim", "projection", "section", "distance", "collision", "motion"]
    prof = _PROFILE = CompileProfile().start() if profile else None
    G = _groups()
    for name in order:
        if prof is not None:
            prof.mark(name)
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            G[name]()
            err = ""
        except Exception as e:  # report and go on with the next group
            err = f"  ERROR {type(e).__name__}: {e}"
        print(f"{name:12s} first call: cpu {time.process_time() - c0:6.1f} s  "
              f"wall {time.perf_counter() - w0:6.1f} s{err}", flush=True)
        if name == "demo":
            continue
        w0, c0 = time.perf_counter(), time.process_time()
        G[name]()
        print(f"{name:12s} second call: cpu {time.process_time() - c0:6.2f} s", flush=True)
    if prof is not None:
        prof.stop()
        prof.report()


if __name__ == "__main__":
    main()
