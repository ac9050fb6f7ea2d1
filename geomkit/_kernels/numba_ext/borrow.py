"""Unmanaged views of arrays for hot loops: no atomic reference counting.

numba counts references to every array it passes, views or rebinds: each count is an
atomic add on the array's shared memory-info block (``NRT_incref`` /
``NRT_decref``).  Its reference-count pruning removes pairs within one basic block,
not across the branches of a loop body, and helpers inlined at the IR level
(:data:`geomkit._kernels.numba_ext.policy.jit_inline`) bind their array arguments to new
variables, each counted.  Measured in the projection's candidate search on the plate
(``perf``, one thread): 55 % of the time was spent in those two functions.

:func:`borrow` returns the same array without its memory-info block: numba's counting
then sees a null pointer and does nothing (a test and a return instead of an atomic
operation).  The caller must keep the owner alive while the view is used: borrow only
the arguments of a kernel (its caller holds them) or arrays the kernel passes on to a
callee that borrows them; never return a borrowed array to Python.
"""

from __future__ import annotations

from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload


@intrinsic
def borrow(typingctx, arr):
    """``arr`` without its memory-info block and parent (same type, same data, shape
    and strides): an unmanaged view, valid while the owner lives."""
    if not isinstance(arr, types.Array):
        return None
    sig = arr(arr)

    return sig, _codegen


def _codegen(context, builder, signature, args):
    return _borrow_value(context, builder, signature.args[0], args[0])


def _borrowable(ty):
    """Arrays, numbers and (nested) tuples of them: nothing else counted."""
    if isinstance(ty, types.BaseTuple):
        return all(_borrowable(t) for t in ty)
    return isinstance(ty, (types.Array, types.Number, types.Boolean))


def _borrow_value(context, builder, ty, val):
    """The value with every array in it borrowed (recursively through tuples: the
    result is a new reference for numba, so no counted array may pass through)."""
    if isinstance(ty, types.BaseTuple):
        out = cgutils.get_null_value(context.get_value_type(ty))
        for i, t in enumerate(ty):
            v = builder.extract_value(val, i)
            out = builder.insert_value(out, _borrow_value(context, builder, t, v), i)
        return out
    if not isinstance(ty, types.Array):
        return val
    src = context.make_array(ty)(context, builder, value=val)
    dst = context.make_array(ty)(context, builder)
    dst.meminfo = cgutils.get_null_value(dst.meminfo.type)
    dst.parent = cgutils.get_null_value(dst.parent.type)
    dst.nitems = src.nitems
    dst.itemsize = src.itemsize
    dst.data = src.data
    dst.shape = src.shape
    dst.strides = src.strides
    return dst._getvalue()


@intrinsic
def borrow_all(typingctx, tup):
    """:func:`borrow` of every array in the tuple ``tup``, nested tuples included
    (numbers unchanged): ``a, (b, c), n = borrow_all((a, (b, c), n))``."""
    if not (isinstance(tup, types.BaseTuple) and _borrowable(tup)):
        return None
    sig = tup(tup)

    return sig, _codegen


def borrow_opt(x):
    """:func:`borrow` of an array, ``None`` unchanged.

    For kernels specialised on an optional array (``seg_all`` None: untrimmed): the
    view takes a name of its own, as rebinding the argument would keep numba from
    pruning the ``seg_all is None`` branches of the untrimmed specialisation."""
    raise NotImplementedError("only callable from a kernel")


@overload(borrow_opt)
def _borrow_opt(x):
    if isinstance(x, types.NoneType):
        return lambda x: x
    if isinstance(x, types.Array):
        return lambda x: borrow(x)
    return None
