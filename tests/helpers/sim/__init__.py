"""Simulator helpers: the server contract every endpoint's tests subclass, packets, the
sans-I/O model's rig and socket peers, the simulator as a process (and one a test powers off
and on), the firmwares a test runs against."""
