"""The Qt-free engine: session state, fixed-rate loop, server."""
