"""Compile time per kernel group: run in a fresh interpreter with an empty cache,

    NUMBA_CACHE_DIR=$(mktemp -d) python -m geomkit.bench.compile_groups

Prints the CPU and wall time of the first and second call of each group (the
difference is the compile time; later groups reuse what earlier ones compiled).
See docs/compile.md."""


def main():
    import sys
    import time
    order = sys.argv[1].split(",") if len(sys.argv) > 1 else \
        ["tessellate", "trim", "projection", "section", "distance", "collision", "motion"]
    import numpy as np
    import geomkit
    from geomkit import samples
    surf = samples.load("freeform_1")[0]
    plate = samples.load("plate_with_hole")[0]
    def g_tess(): geomkit.tessellate(surf, 1e-2)
    def g_trim(): geomkit.classify_uv(plate, np.array([[0.5, 0.5], [0.1, 0.2]]))
    def g_proj():


        geomkit.project_points(plate, np.array([[50, 50, 3.0], [10, 10, 1.0]]))
    def g_sec(): geomkit.plane_section(surf, np.array([1.0, 0, 0, -50.0]), 1e-4)
    def g_dist():
        a, b = samples.load("sphere_pair"); geomkit.surface_distance(a, b, tol=1e-6)
    def g_coll():
        m = geomkit.tessellate(samples.load("sphere")[0], 1e-1)
        A = geomkit.Body(m); T = np.eye(4); T[0, 3] = 5.0
        geomkit.collide(A, np.eye(4), A, T); geomkit.min_distance(A, np.eye(4), A, T)
    def g_motion():
        m = geomkit.tessellate(samples.load("sphere")[0], 1e-1)
        A = geomkit.Body(m); T = np.eye(4); T[0, 3] = 30.0
        geomkit.first_contact(A, np.eye(4), np.zeros(3), A, T, np.array([-1.0, 0, 0]), 30.0)
    G = dict(tessellate=g_tess, trim=g_trim, projection=g_proj, section=g_sec, distance=g_dist,
             collision=g_coll, motion=g_motion)
    for name in order:
        w0, c0 = time.perf_counter(), time.process_time()
        try:
            G[name]()
            err = ""
        except Exception as e:
            err = f"  ERROR {type(e).__name__}: {e}"
        print(f"{name:12s} first call: cpu {time.process_time()-c0:6.1f} s  wall {time.perf_counter()-w0:6.1f} s{err}", flush=True)
        w0, c0 = time.perf_counter(), time.process_time()
        G[name]()
        print(f"{name:12s} second call: cpu {time.process_time()-c0:6.2f} s", flush=True)


if __name__ == "__main__":
    main()
