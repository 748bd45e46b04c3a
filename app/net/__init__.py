"""The engine's message protocol: message schemas, the msgpack codec, typed snapshots, the ZeroMQ
transport and its security (docs/protocol.md)."""
