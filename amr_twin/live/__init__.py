"""Live view and teleop: the Foxglove WebSocket server, the live Rerun stream, real-time pacing and client inputs."""
