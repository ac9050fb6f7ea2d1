"""Build hook: the ahead-of-time compiled kernels (docs/compile.md).

Everything else is in pyproject.toml.  ``build_ext`` runs
``geomkit/_kernels/numba_ext/aot_build.py build`` (numba's pycc) in a child process and puts the
extension module ``geomkit/_kernels/numba_ext/aot_lib`` and its manifest into the build (or,
for ``pip install -e .``, into the source tree).  The AOT build never fails the
install: if it fails the package is installed without it and runs on the JIT
(``geomkit --version`` says which).  ``GEOMKIT_NO_AOT=1`` skips it.
"""

import os
import subprocess
import sys
import time
from pathlib import Path

from setuptools import setup
from setuptools.command.build_ext import build_ext
from setuptools.dist import Distribution

ROOT = Path(__file__).resolve().parent
KERNELS = ("geomkit", "_kernels", "numba_ext")


class BinaryDistribution(Distribution):
    """A platform wheel: it holds a compiled module (when the AOT build succeeds)."""

    def has_ext_modules(self):
        return True


class build_aot(build_ext):
    def run(self):
        super().run()
        self._aot_outputs = []
        out = (ROOT if self.inplace else Path(self.build_lib)).joinpath(*KERNELS)
        out.mkdir(parents=True, exist_ok=True)
        man = out / "aot_manifest.json"
        for old in list(out.glob("aot_lib*")) + [man]:  # a previous build's
            if old.exists():
                old.unlink()
        if os.environ.get("GEOMKIT_NO_AOT", "") not in ("", "0"):
            print("geomkit: GEOMKIT_NO_AOT set: no ahead-of-time kernels (JIT)")
            return
        t0 = time.time()
        try:
            # by path, without geomkit/__init__.py (see aot_build.by_path_command)
            code = ("import runpy, sys; sys.argv = sys.argv[1:]; "
                    "runpy.run_path(sys.argv[0], run_name='__main__')")
            tool = ROOT.joinpath(*KERNELS, "aot_build.py")
            r = subprocess.run([sys.executable, "-c", code, str(tool), "build", str(out)],
                               cwd=str(ROOT))
            ok = r.returncode == 0 and man.exists()
        except Exception as e:  # never fail the install
            print(f"geomkit: ahead-of-time build did not run: {e}")
            ok = False
        if not ok:
            for f in list(out.glob("aot_lib*")) + [man]:
                if f.exists():
                    f.unlink()
            print("geomkit: WARNING: the ahead-of-time kernel build failed; geomkit "
                  "will compile its kernels on first use (JIT)")
            return
        print(f"geomkit: ahead-of-time kernels built in {time.time() - t0:.0f} s")
        self._aot_outputs = [str(p) for p in out.glob("aot_lib*")] + [str(man)]

    def get_outputs(self):
        return super().get_outputs() + list(getattr(self, "_aot_outputs", []))


setup(distclass=BinaryDistribution, cmdclass={"build_ext": build_aot})
