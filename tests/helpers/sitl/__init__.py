"""ArduPilot SITL helpers: a real XF host against the simulator."""
