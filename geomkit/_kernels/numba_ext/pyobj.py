"""Python objects handed to a compiled entry point as they are (by address).

A call into a numba entry point converts every argument: ~30 ns for an integer
above 2**30 (an address), ~60 ns for an array (numba allocates a memory-info block
for it), and the caller must first check an array's dtype and dimensions, since the
entry point of a fixed signature does not.  On a call answered in ~0.1 µs (a
single :func:`geomkit.collide` whose root boxes are disjoint) that conversion was
most of the cost.

An argument typed :data:`object_ref` is not converted: the kernel receives the
object's address (:func:`address`), borrowed from the caller, who keeps the object
alive for the call.  The kernel reads what it needs through the layouts below and
checks the object's type itself: :func:`array_data` accepts only an exact
``numpy.ndarray`` of a given dtype (any other object, a subclass or another dtype
gives 0, and nothing of it is read past its type).

The layouts are CPython's object header, NumPy's ``PyArrayObject_fields``
(unchanged from NumPy 1.7 to 2.x) and the dtype descriptor's codes;
:func:`array_fields_ok` checks them against a live array, and a caller uses
``object_ref`` entry points only when it holds.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import types

from numba.extending import NativeValue, intrinsic, models, register_model, unbox

from .policy import jit_inline

OB_TYPE = 8
"""Byte offset of an object's type pointer (CPython's ``PyObject`` header)."""
DATA, NDIM, DIMS, STRIDES, DESCR = 16, 24, 32, 40, 56
"""Byte offsets in an ``ndarray`` object of NumPy's ``data``, ``nd`` (C int),
``dimensions``, ``strides`` and ``descr`` (``PyArrayObject_fields``)."""
DESCR_CODES = 24
"""Byte offset in a dtype descriptor of ``kind``, ``type``, ``byteorder`` (+2) and,
from +4, ``type_num`` (C int): the same in NumPy 1.x and 2.x."""
NPY_DOUBLE = 12
"""NumPy's ``type_num`` of float64."""


class ObjectRef(types.Type):
    """Numba type of an argument passed as the Python object's address."""

    def __init__(self):
        super().__init__(name="ObjectRef")


object_ref = ObjectRef()
register_model(ObjectRef)(models.OpaqueModel)


@unbox(ObjectRef)
def _unbox_object_ref(typ, obj, c):
    return NativeValue(obj)       # the PyObject* itself: no conversion, no reference


@intrinsic
def address(typingctx, ref):
    """The address (int64) of the object passed as ``ref`` (:data:`object_ref`)."""
    if not isinstance(ref, ObjectRef):
        return None
    sig = types.int64(ref)

    def codegen(context, builder, signature, args):
        return builder.ptrtoint(args[0], ir.IntType(64))
    return sig, codegen


def _pointer_to(item):
    """An intrinsic: the pointer to ``item`` at an int64 address."""
    @intrinsic
    def pointer(typingctx, addr):
        sig = types.CPointer(item)(types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(signature.return_type))
        return sig, codegen
    return pointer


i64_ptr = _pointer_to(types.int64)
"""The int64 pointer at the int64 address ``addr``."""
f64_ptr = _pointer_to(types.float64)
"""The float64 pointer at the int64 address ``addr``."""


@intrinsic
def f64_load(typingctx, addr):
    """The float64 stored at the int64 address ``addr``."""
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        return builder.load(builder.inttoptr(args[0], ir.DoubleType().as_pointer()))
    return sig, codegen


@jit_inline
def array_data(obj, ndarray, descr, type_num, ndim):
    """``(data, dims, strides)`` addresses of the object at the address ``obj`` if it
    is exactly a ``numpy.ndarray`` (type object at the address ``ndarray``) with
    ``ndim`` dimensions and a native-order dtype of ``type_num`` (the descriptor at
    ``descr``, the usual one, or any other with that number: e.g. an unpickled
    array's own copy), else ``(0, 0, 0)``."""
    if obj == 0 or i64_ptr(obj + OB_TYPE)[0] != ndarray:
        return 0, 0, 0
    if (i64_ptr(obj + NDIM)[0] & 0xFFFFFFFF) != ndim:
        return 0, 0, 0
    d = i64_ptr(obj + DESCR)[0]
    if d != descr:
        codes = i64_ptr(d + DESCR_CODES)[0]
        if (codes >> 32) & 0xFFFFFFFF != type_num or (codes >> 16) & 0xFF == 62:  # '>'
            return 0, 0, 0
    return i64_ptr(obj + DATA)[0], i64_ptr(obj + DIMS)[0], i64_ptr(obj + STRIDES)[0]


def array_fields_ok():
    """Do a live array's type, data, ndim, shape, strides and dtype codes sit at the
    offsets the kernels read (:data:`OB_TYPE`, :data:`DATA` ... :data:`DESCR_CODES`)?
    False on another Python implementation or an incompatible NumPy.  (Each address
    read is one the layout being checked has already been found right about.)"""
    import ctypes
    import platform
    if platform.python_implementation() != "CPython":
        return False
    x = np.arange(16.0).astype(np.dtype(np.float64, metadata={"k": 0}))
    x = x.reshape(4, 4)[:, ::-1]
    at = id(x)

    def i64(addr):
        return ctypes.c_int64.from_address(addr).value
    if i64(at + OB_TYPE) != id(np.ndarray) or i64(at + DATA) != x.ctypes.data \
            or i64(at + NDIM) & 0xFFFFFFFF != 2 or i64(at + DESCR) != id(x.dtype):
        return False
    codes = i64(id(x.dtype) + DESCR_CODES)
    return ((codes >> 32) & 0xFFFFFFFF == NPY_DOUBLE == x.dtype.num
            and chr((codes >> 16) & 0xFF) == x.dtype.byteorder
            and [i64(i64(at + DIMS) + 8 * k) for k in range(2)] == [4, 4]
            and [i64(i64(at + STRIDES) + 8 * k) for k in range(2)] == list(x.strides))
