"""Session helpers: the virtual-time rig, the same on a modelled asyncio loop, a scripted GCU."""
