"""Simulator helpers: packets, the sans-I/O model's rig and socket peers, the simulator as a
process (and one a test powers off and on), the firmwares a test runs against."""
