"""The GCU link as the bridge reads it: may a command go to the GCU now, and has the
client given up (docs/mavlink-bridge.md, "The bridge contract", BG4 and BG9).

**Ready** means the client is open, its session counts the link up, and the last reply is
at most the session's ``control_silence`` old: new control values then go out valid from
the next host packet, and a command goes to a GCU that answered a moment ago. While not
ready, commands wait (within their 2 s), and a setpoint is not taken: a GCU that stopped
answering would get it, valid, whenever replies return.

The bridge reopens a client whose transport gave up (state ``FAILED``, event ``GAVE_UP``)
and forgets what it set on the GCU after a restart (event ``RESTARTED``).
"""

from __future__ import annotations

from gcu_async.client.client import ClientState, GcuClient
from gcu_async.transport.base import LinkEvent, LinkEventKind


def ready(client: GcuClient) -> bool:
    """May a command or new control values go to the GCU now (module docstring)?"""
    if client.state is not ClientState.OPEN:
        return False
    health = client.link
    age = health.last_reply_age
    return health.up and age is not None and age <= client.session.config.control_silence


def opened(client: GcuClient) -> bool:
    """Is the client open (its heartbeat running), whether or not replies arrive?"""
    return client.state is ClientState.OPEN


def failed(client: GcuClient) -> bool:
    """Has the client's transport given up reconnecting (the bridge then reopens it)?"""
    return client.state is ClientState.FAILED


def gave_up(event: LinkEvent) -> bool:
    return event.kind is LinkEventKind.GAVE_UP


def restarted(event: LinkEvent) -> bool:
    return event.kind is LinkEventKind.RESTARTED
