"""Transport helpers: the transport contract, its recorder, the fault-injecting UDP proxy, an
asyncio loop on virtual time."""
