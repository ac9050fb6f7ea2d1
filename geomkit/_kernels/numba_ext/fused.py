"""A fused multiply-add that kernels call by name: ``fma(a, b, c)`` is ``a * b + c``
rounded once (LLVM's ``llvm.fma.f64``: the FMA instruction where the processor has
one, a correctly rounded library call otherwise).

Contraction (``fastmath`` ``contract``) leaves to LLVM which product of a sum it fuses;
a kernel that must reproduce a fixed order of fused operations (OpenBLAS's ``ddot``
on a few elements, which numpy's 1-D ``dot`` calls) names each one.
"""

from __future__ import annotations

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic


@intrinsic
def fma(typingctx, a, b, c):
    """``a * b + c`` with one rounding (float64 arguments)."""
    if not all(isinstance(t, types.Float) and t.bitwidth == 64 for t in (a, b, c)):
        return None
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        d = ir.DoubleType()
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(d, [d, d, d]),
                                            "llvm.fma.f64")
        return builder.call(fn, args)

    return sig, codegen
