"""Build the ahead-of-time compiled kernels (see :mod:`geomkit._kernels.numba_ext.aot`).

Not a kernel: the build tool, kept here (with the loader) so that it imports only
``geomkit._kernels``; files named ``aot*`` are outside the kernel source stamp.

::

    python geomkit/_kernels/numba_ext/aot_build.py record      # regenerate numba_ext/aot_exports.json
    python geomkit/_kernels/numba_ext/aot_build.py build [DIR] # compile aot_lib + manifest into DIR

``record`` runs ``geomkit demo`` and then the real parts of ``tests/data/parts`` (read,
mesh, section, project: ``geomkit.bench.parts.exercise``) in a child process with
``GEOMKIT_AOT_RECORD`` set:
every kernel call made *from Python* is recorded with its argument types (calls from
other kernels are compiled code and never pass through Python), and those are the
exports.  ``build`` compiles each export with numba's ``pycc`` into one extension
module, with the flags the JIT uses for the kernel (``nopython``, ``nogil`` -- the
wrapper releases the GIL, so :func:`geomkit._kernels.numba_ext.policy.prun` keeps both cores
busy --, ``fastmath={"contract", "nsz"}``, ``error_model="numpy"``) and for the host
CPU with the host's feature flags (as the JIT: the same code, bit for bit; a
generic CPU would give up FMA contraction and change results).  It runs in its own
process with an empty numba cache, and ``setup.py`` ignores its failure.
"""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
import tempfile
import time
from importlib import import_module
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

if __name__ == "__main__" and not __package__:
    # run by path (setup.py, in pip's isolated build environment, which has numba and
    # numpy but not geomkit's other dependencies): import geomkit._kernels without
    # geomkit/__init__.py
    import types as _types

    _pkg = _types.ModuleType("geomkit")
    _pkg.__path__ = [str(ROOT / "geomkit")]
    sys.modules.setdefault("geomkit", _pkg)
    __package__ = "geomkit._kernels.numba_ext"

from . import aot as _aot  # noqa: E402


def record(out=_aot.EXPORTS, grid=None, parts=True) -> list:
    """Run the demo with call recording and write the export list to ``out``; with
    ``parts``, then geomkit's side of the parts benchmark on the repository's real
    parts (``geomkit.bench.parts.exercise``: read, mesh, section, project), so that a
    real part's first calls on a fresh install are compiled code too."""
    with tempfile.TemporaryDirectory(prefix="geomkit-aot-rec-") as tmp:
        rec = Path(tmp) / "rec.json"
        env = dict(os.environ, GEOMKIT_AOT_RECORD=str(rec), GEOMKIT_AOT="0")
        env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + ([env["PYTHONPATH"]]
                                                           if env.get("PYTHONPATH") else []))
        code = ("from geomkit.jobs.demo import run_demo; "
                f"run_demo({str(Path(tmp) / 'demo')!r}, warm_up=False"
                + (f", grid={grid}" if grid else "") + ")"
                + ("; from geomkit.bench.parts import exercise; exercise()" if parts else ""))
        subprocess.run([sys.executable, "-c", code], env=env, check=True,
                       stdout=subprocess.DEVNULL)
        rows = json.loads(rec.read_text())
    keep, skipped = [], []
    for mod, qual, sig in rows:
        try:
            [_aot.parse_type(s) for s in sig]
        except ValueError as e:
            skipped.append((mod, qual, str(e)))
            continue
        keep.append([mod, qual, sig])
    if out is not None:
        Path(out).write_text(json.dumps(keep, indent=1) + "\n")
    for s in skipped:
        print("not exported:", *s, file=sys.stderr)
    return keep


def _flags_for(disp):
    """The numba compile flags the JIT uses for dispatcher ``disp``."""
    from numba.core import compiler

    flags = compiler.Flags()
    disp.targetdescr.options.parse_as_flags(flags, disp.targetoptions)
    return flags


def build(out_dir, exports=None, verbose=False) -> dict:
    """Compile the exports into ``out_dir/aot_lib*.so`` and write the manifest next
    to it; returns the manifest."""
    from numba.core import codegen
    from numba.pycc import CC
    from numba.pycc import compiler as pycc_compiler

    import numba

    from . import policy

    t0 = time.time()
    out_dir = Path(out_dir)
    rows = json.loads(_aot.EXPORTS.read_text()) if exports is None else exports
    # pycc compiles a module with one set of flags: one module per set, the first
    # (the first export's: the JIT's default) aot_lib, the others (jit_exact: no
    # contraction) aot_lib_1, ...
    groups = []  # [flags, CC, lib name]
    entries = []
    for k, (mod, qual, sig) in enumerate(rows):
        obj = import_module(mod)
        for part in qual.split("."):
            obj = getattr(obj, part)
        disp = getattr(obj, "dispatcher", obj)
        f = _flags_for(disp)
        g = next((g for g in groups if g[0] == f), None)
        if g is None:
            lib = _aot.LIB_NAME if not groups else f"{_aot.LIB_NAME}_{len(groups)}"
            cc = CC(lib)
            cc.output_dir = str(out_dir)
            cc.verbose = verbose
            cc.target_cpu = "host"
            g = [f, cc, lib]
            groups.append(g)
        sym = _aot.export_symbol(mod, qual, k)
        g[1].export(sym, tuple(_aot.parse_type(s) for s in sig))(disp.py_func)
        entries.append([mod, qual, k, sig, g[2]])

    # pycc compiles with a bare Flags(): patch it to the JIT's flags, and give the AOT
    # code generator the host's CPU features (the JIT's) rather than only the model's
    host_features = codegen.JITCPUCodegen._get_host_cpu_features(None)
    # (pycc passes one Flags object to every export's compile, and a compile changes
    # it: each gets its own copy, as each JIT compile gets fresh flags)
    saved = (pycc_compiler.Flags, pycc_compiler.compile_extra,
             codegen.AOTCPUCodegen._customize_tm_features)
    compile_extra = pycc_compiler.compile_extra

    def compile_copy(typingctx, targetctx, func, args, return_type, fl, **kw):
        return compile_extra(typingctx, targetctx, func, args, return_type,
                             copy.deepcopy(fl), **kw)
    pycc_compiler.compile_extra = compile_copy
    codegen.AOTCPUCodegen._customize_tm_features = lambda self: host_features
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        old = out_dir / _aot.MANIFEST.name
        if old.exists():  # no manifest until the new modules are complete
            old.unlink()
        for flags, cc, _ in groups:
            pycc_compiler.Flags = lambda flags=flags: copy.deepcopy(flags)
            cc.compile()
    finally:
        (pycc_compiler.Flags, pycc_compiler.compile_extra,
         codegen.AOTCPUCodegen._customize_tm_features) = saved
    manifest = {"stamp": policy._kernels_stamp().hex(), "numba": numba.__version__,
                "cpu": list(_aot.host_cpu()), "exports": entries,
                "built_seconds": round(time.time() - t0, 1)}
    (out_dir / _aot.MANIFEST.name).write_text(json.dumps(manifest, indent=1) + "\n")
    return manifest


def by_path_command(*argv) -> list:
    """The command running this file by path, not as ``python FILE`` (that would put
    ``geomkit/`` first on ``sys.path``, where ``types.py`` hides the standard library's)."""
    code = ("import runpy, sys; sys.argv = sys.argv[1:]; "
            "runpy.run_path(sys.argv[0], run_name='__main__')")
    return [sys.executable, "-c", code, str(Path(__file__).resolve()), *map(str, argv)]


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv[:1] == ["record"]:
        rows = record()
        print(f"{len(rows)} exports written to {_aot.EXPORTS}")
        return 0
    if argv[:1] == ["build"]:
        out = Path(argv[1]) if len(argv) > 1 else _aot.HERE
        if not os.environ.get("_GEOMKIT_AOT_CHILD"):
            # a child with an empty numba cache: the exports' callees are compiled
            # there from source (their LLVM code is linked into the module), never
            # loaded from a cache, and no cache file is left behind
            with tempfile.TemporaryDirectory(prefix="geomkit-aot-cache-") as tmp:
                env = dict(os.environ, NUMBA_CACHE_DIR=tmp, _GEOMKIT_AOT_CHILD="1",
                           GEOMKIT_AOT="0")
                env["PYTHONPATH"] = os.pathsep.join(
                    [str(ROOT)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
                return subprocess.run(by_path_command(*argv), env=env).returncode
        man = build(out, verbose="-v" in argv)
        print(f"built {len(man['exports'])} ahead-of-time entries into {out} "
              f"in {man['built_seconds']} s")
        return 0
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main())
