"""Exceptions raised by the modskill client."""

from __future__ import annotations

import grpc

__all__ = ["ServerError", "ConnectError"]


class ServerError(Exception):
    """A call failed on the server (or on the way to it).

    Attributes:
      code: the gRPC status code, a ``grpc.StatusCode`` (for example ``NOT_FOUND``,
        ``INVALID_ARGUMENT``, ``FAILED_PRECONDITION``, ``UNAUTHENTICATED``).
      message: the server's message, unchanged; by the contract it names the offending field.
      server: the address the client talked to.
      rpc: the RPC that failed (``"Describe"``, ``"Simulate"``, ...), when known.
    """

    def __init__(self, code: grpc.StatusCode, message: str, server: str = "", rpc: str = ""):
        self.code = code
        self.message = message
        self.server = server
        self.rpc = rpc
        super().__init__(str(self))

    def __str__(self) -> str:
        where = " ".join(part for part in (self.rpc, f"on {self.server}" if self.server else "") if part)
        name = self.code.name if isinstance(self.code, grpc.StatusCode) else str(self.code)
        return f"{name}: {self.message}" + (f" ({where})" if where else "")

    def __reduce__(self):  # picklable (multiprocessing workers)
        return (type(self), (self.code, self.message, self.server, self.rpc))

    @classmethod
    def from_rpc_error(cls, error: grpc.RpcError, server: str = "", rpc: str = "") -> "ServerError":
        """Wraps a ``grpc.RpcError`` raised by a call, keeping its code and details."""
        code = error.code() if hasattr(error, "code") else grpc.StatusCode.UNKNOWN
        details = error.details() if hasattr(error, "details") else str(error)
        return cls(code if code is not None else grpc.StatusCode.UNKNOWN, details or "", server, rpc)


class ConnectError(ServerError):
    """No server answered at the address within the client's timeout (code ``UNAVAILABLE``)."""
