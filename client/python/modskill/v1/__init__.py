"""Generated protocol modules of proto/modskill/v1/modskill.proto (``modskill_pb2``,
``modskill_pb2_grpc``), committed so that the package imports without a C++ build tree.

They live here, not in a private subpackage, because the generated gRPC module imports
``modskill.v1.modskill_pb2``: the path follows the .proto's. Do not edit them; after changing
the proto, regenerate with client/python/generate_stubs.sh (test_install.py fails until then).
"""
