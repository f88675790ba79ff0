"""Bridge helpers: the MAVLink rigs, the simulator and floods in processes of their own."""
