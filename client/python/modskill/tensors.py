"""Conversions between ``modskill.v1.Tensor`` messages and numpy arrays.

On the wire a tensor is raw little-endian bytes plus a row-major shape and a dtype
(FLOAT32, INT32 or UINT8). Decoding wraps the message's bytes without copying, so decoded
arrays are read-only views: call ``.copy()`` before writing into one.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from .v1 import modskill_pb2 as pb

__all__ = ["decode", "encode", "encode_float32", "NUMPY_DTYPES"]

# Wire dtype -> numpy dtype (explicitly little-endian).
NUMPY_DTYPES = {
    pb.FLOAT32: np.dtype("<f4"),
    pb.INT32: np.dtype("<i4"),
    pb.UINT8: np.dtype("u1"),
}
_WIRE_DTYPES = {(dtype.kind, dtype.itemsize): wire for wire, dtype in NUMPY_DTYPES.items()}


def decode(tensor: pb.Tensor, field: str = "tensor") -> np.ndarray:
    """Returns the tensor as a read-only numpy array of its shape and dtype.

    Raises ValueError when the dtype is unknown or the byte count does not match the shape.
    """
    dtype = NUMPY_DTYPES.get(tensor.dtype)
    if dtype is None:
        name = pb.DType.Name(tensor.dtype) if tensor.dtype in pb.DType.values() else str(tensor.dtype)
        raise ValueError(f"{field}.dtype: {name} cannot be decoded (FLOAT32, INT32 or UINT8)")
    shape = tuple(int(d) for d in tensor.shape)
    if any(d < 0 for d in shape):
        raise ValueError(f"{field}.shape: {list(shape)} has a negative dimension")
    count = int(np.prod(shape, dtype=np.int64)) if shape else 1
    if len(tensor.data) != count * dtype.itemsize:
        raise ValueError(f"{field}.data: {len(tensor.data)} bytes, shape {list(shape)} of "
                         f"{pb.DType.Name(tensor.dtype)} needs {count * dtype.itemsize}")
    return np.frombuffer(tensor.data, dtype=dtype, count=count).reshape(shape)


def decode_field(message, name: str) -> Optional[np.ndarray]:
    """Decodes ``message.<name>``, or returns None when the field is not set."""
    if not message.HasField(name):
        return None
    return decode(getattr(message, name), name)


def encode(array: np.ndarray, out: Optional[pb.Tensor] = None) -> pb.Tensor:
    """Encodes a float32, int32 or uint8 array (any byte order) as a Tensor message."""
    array = np.asarray(array)
    wire = _WIRE_DTYPES.get((array.dtype.kind, array.dtype.itemsize))
    if wire is None:
        raise ValueError(f"dtype {array.dtype} has no wire dtype (float32, int32 or uint8)")
    out = pb.Tensor() if out is None else out
    del out.shape[:]
    out.shape.extend(array.shape)
    out.dtype = wire
    out.data = np.ascontiguousarray(array, dtype=NUMPY_DTYPES[wire]).tobytes()
    return out


def encode_float32(array: np.ndarray, out: Optional[pb.Tensor] = None) -> pb.Tensor:
    """Encodes any real array as a FLOAT32 tensor (converting, little-endian)."""
    return encode(np.ascontiguousarray(array, dtype="<f4"), out)
