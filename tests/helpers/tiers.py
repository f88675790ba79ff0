"""Which tier each test belongs to: the table ``make test``, ``make check`` and CONTRIBUTING.md's
"Test tiers" work from.

Every test has exactly one *kind*:

``fast``
    sans-I/O, in-memory transports, virtual time (tests/helpers/session/vtime.py), pure argument
    checks. Runs on every CPython in ``make test`` and in ``make check``.
``realtime``, ``subprocess``, ``netns``, ``browser``, ``tshark``, ``sitl``
    real-time waits on the event loop (loopback sockets, ptys, in-memory transports on the
    real clock), child processes (the CLI, a simulator process), network namespaces,
    Chromium, tshark/tcpdump, an ArduPilot SITL. The *full* tier: run once per ``make
    test``, on the main interpreter, in parallel (pytest-xdist).

and may also be ``alone``: it cannot share the machine (it measures a rate or real-time
latency against a bound the protocol sets), so ``make test`` runs it after the parallel phase,
one test at a time. Only full-tier tests can be ``alone``. A ``fast`` test that runs for many
seconds of CPU at full size (the session contract's shards, the deframer and round-trip
properties) is also ``heavy``: the main run spreads it over the pytest-xdist workers instead of
running it in the fast tier's one process. Only for files of few tests: pytest-xdist costs
milliseconds a test.

A test's kind comes from the closest of: its own marker (``@pytest.mark.realtime`` on the test
or class, or a module-level ``pytestmark``), else its file's entry in :data:`TIERS`. A file in
neither gets the full tier by default (so it still runs once on the main interpreter, never
silently nowhere) and tests/project/test_tiers.py fails until it has an entry.
"""

from __future__ import annotations

FAST = "fast"
SLOW_KINDS = ("realtime", "subprocess", "netns", "browser", "tshark", "sitl")
KINDS = (FAST, *SLOW_KINDS)
ALONE = "alone"
HEAVY = "heavy"
DEFAULT = "realtime"
"""The kind of a test in no table and with no marker: full tier, main interpreter only."""

MARKERS = {
    FAST: "sans-I/O, in-memory or virtual-time: every interpreter and `make check`",
    "realtime": "real-time waits: loopback sockets, ptys, in-memory transports on the real "
    "clock (full tier: main interpreter)",
    "subprocess": "starts processes: the CLI, a simulator process, a pty (full tier)",
    "netns": "network namespaces, needs root and iproute2 (full tier)",
    "browser": "Chromium through Playwright (full tier)",
    "tshark": "tshark, tcpdump or dumpcap (full tier)",
    "sitl": "an ArduPilot SITL, GCU_ARDUPILOT_SITL (full tier)",
    ALONE: "cannot share the machine (measures a rate or latency): run after the parallel "
    "phase, one at a time",
    HEAVY: "a fast test with many seconds of CPU at full size: the main run gives it to the "
    "pytest-xdist workers",
}

TIERS: dict[str, str | tuple[str, ...]] = {
    "test_aircraft_feed.py": FAST,
    "test_protocol_aircraft_update.py": FAST,
    "test_protocol_frame_code.py": FAST,
    "test_protocol_frame_schema.py": FAST,
    "test_protocol_decode_differential.py": FAST,
    "test_aircraft_feed_sockets.py": "subprocess",
    "test_bench_capacity.py": "subprocess",
    "test_bridge_admission.py": FAST,
    "test_bridge_adversarial.py": ("subprocess", ALONE),
    "test_bridge_autopilot.py": "realtime",
    "test_bridge_autopilot_values.py": FAST,
    "test_bridge_camera.py": "realtime",
    "test_bridge_cli.py": "subprocess",
    "test_bridge_command_rules.py": "realtime",
    "test_bridge_fairness.py": ("subprocess", ALONE),
    "test_bridge_gcu_link.py": FAST,
    "test_bridge_gcu_outage.py": "realtime",
    "test_bridge_gimbal.py": "realtime",
    "test_bridge_z1pro.py": "realtime",
    "test_bridge_links.py": ("realtime", ALONE),
    "test_bridge_links_endpoint.py": FAST,
    "test_bridge_mapping.py": FAST,
    "test_bridge_outage_matrix.py": "subprocess",
    "test_bridge_mavsdk.py": "realtime",
    "test_bridge_qgc.py": "realtime",
    "test_bridge_rig.py": "realtime",
    "test_capture_blocks.py": FAST,
    "test_capture_independent.py": ("tshark", ALONE),  # 200 packets/s, counted
    "test_capture_library.py": "tshark",
    "test_capture_memory.py": "subprocess",
    "test_capture_reassembly.py": FAST,
    "test_capture_scan.py": FAST,
    "test_capture_streams.py": FAST,
    "test_catalogue.py": FAST,
    "test_ci_pythons.py": "subprocess",
    "test_cli_cuts.py": "subprocess",
    "test_cli_demo.py": "subprocess",
    "test_cli_exit_status.py": "subprocess",
    "test_cli_monitor.py": "subprocess",
    "test_cli_monitor_passive.py": "subprocess",
    "test_cli_passive_rules.py": FAST,
    "test_cli_usage_style.py": FAST,
    "test_cli_negative_values.py": FAST,
    "test_cli_gcu_report.py": "subprocess",
    "test_cli_decode_report.py": "subprocess",
    "test_cli_new_user.py": "subprocess",
    "test_cli_send_monitor.py": "subprocess",
    "test_client_behaviour.py": "realtime",
    "test_client_builder.py": FAST,
    "test_client_boundary.py": FAST,
    "test_client_new_user.py": "realtime",
    "test_client_open_retry.py": "realtime",
    "test_client_outages.py": FAST,
    "test_client_robustness.py": ("realtime", ALONE),  # exactly once needs delays < the guard
    "test_client_session.py": "realtime",
    "test_client_waiting.py": "realtime",
    "test_client_firmware.py": "realtime",
    "test_client_second_pass.py": "realtime",
    "test_client_wirelog.py": "subprocess",
    "test_conformance_report.py": FAST,
    "test_conformance_gcu.py": FAST,
    "test_connect_signature.py": FAST,
    "test_connect_typing.py": "subprocess",
    "test_docs_architecture.py": FAST,
    "test_docs_as_dict.py": FAST,
    "test_docs_commands.py": FAST,
    "test_docs_error_tree.py": FAST,
    "test_docs_examples.py": "subprocess",
    "test_docs_generated.py": FAST,
    "test_docs_links.py": FAST,
    "test_docs_pages.py": FAST,
    "test_docs_snippets.py": "subprocess",
    "test_errors_structured.py": FAST,
    "test_example_autopilot.py": "subprocess",
    "test_example_harness.py": "subprocess",
    "test_example_web.py": "realtime",
    "test_example_web_bodies.py": "subprocess",
    "test_example_web_browser.py": "browser",
    "test_example_web_browser_security.py": "browser",
    "test_example_web_cli.py": "subprocess",
    "test_example_web_security.py": "realtime",
    "test_fault_proxy.py": "realtime",
    "test_import_graph.py": FAST,
    "test_module_size.py": FAST,
    "test_no_exec.py": FAST,
    "test_mavlink_mapping.py": FAST,
    "test_netns_lan.py": "netns",
    "test_netns_passive.py": "netns",
    "test_netns_shared_port.py": "netns",
    "test_netns_tcp.py": "netns",
    "test_netns_udp.py": "netns",
    "test_packaging.py": "subprocess",
    "test_platforms.py": "subprocess",
    "test_protocol_boundary.py": FAST,
    "test_protocol_camera_axes.py": FAST,
    "test_protocol_cli_decode.py": "subprocess",
    "test_protocol_crc.py": FAST,
    "test_protocol_decode_errors.py": FAST,
    "test_protocol_deframer.py": (FAST, HEAVY),
    "test_protocol_deframer_contract.py": (FAST, HEAVY),
    "test_protocol_feedback.py": FAST,
    "test_protocol_gpstime.py": FAST,
    "test_protocol_liberal.py": (FAST, HEAVY),
    "test_protocol_liberal_frames.py": FAST,
    "test_protocol_headings.py": FAST,
    "test_protocol_pods.py": FAST,
    "test_protocol_ranges.py": FAST,
    "test_protocol_roundtrip.py": (FAST, HEAVY),
    "test_protocol_schema.py": FAST,
    "test_protocol_vectors.py": FAST,
    "test_public_surface.py": FAST,
    "test_pytest_plugin_without_asyncio.py": "subprocess",
    "test_self_contained.py": "subprocess",
    "test_schema_literals_once.py": FAST,
    "test_session_contract.py": (FAST, HEAVY),  # 100,000 commands in 8 shards
    "test_session_config.py": FAST,
    "test_session_decode_memo.py": FAST,
    "test_session_deviation_log.py": FAST,
    "test_session_gate.py": FAST,
    "test_session_heartbeat_sockets.py": ("subprocess", ALONE),
    "test_session_pacing.py": FAST,
    "test_session_regressions.py": FAST,
    "test_session_restart.py": FAST,
    "test_session_rig.py": FAST,
    "test_session_sockets.py": ("realtime", ALONE),  # reordering below the 15 ms guard
    "test_sim_cli.py": "subprocess",
    "test_sim_cli_report.py": "subprocess",
    "test_sim_exports.py": FAST,
    "test_sim_firmware.py": FAST,
    "test_sim_execution_log.py": FAST,
    "test_sim_fast_path.py": FAST,
    "test_sim_fault_bounds.py": FAST,
    "test_sim_faults.py": "realtime",
    "test_sim_liberal_udp.py": "realtime",
    "test_sim_memory.py": FAST,
    "test_sim_model_camera.py": FAST,
    "test_sim_model_motion.py": FAST,
    "test_sim_model_rules.py": FAST,
    "test_sim_pty.py": "realtime",
    "test_sim_stall.py": "realtime",
    "test_sim_tcp.py": "realtime",
    "test_sim_tolerance.py": FAST,
    "test_sim_udp.py": "realtime",
    "test_sitl_ardupilot.py": "sitl",
    "test_sitl_bridge.py": "sitl",
    "test_sitl_replay.py": FAST,
    "test_tiers.py": FAST,
    "test_transport_memory.py": FAST,
    "test_transport_reconnect_rule.py": FAST,
    "test_transport_serial.py": "realtime",
    "test_transport_registry.py": FAST,
    "test_transport_tcp.py": "realtime",
    "test_transport_tcp_flow.py": "realtime",
    "test_transport_udp.py": "realtime",
    "test_transport_udp_drain.py": "realtime",
    "test_transport_udp_errors.py": "realtime",
    "test_transport_url.py": FAST,  # its loopback end-to-end tests are marked realtime
    "test_wireshark_dissector.py": "tshark",
    "test_wireshark_property.py": "tshark",
    "test_wireshark_headings.py": "tshark",
    "test_wireshark_new_command.py": "tshark",
    "test_wireshark_tables.py": "subprocess",
}
"""Each test file's kind (or ``(kind, ALONE)``, ``(FAST, HEAVY)``). A test marked with a kind
of its own (a subprocess test in a fast file, say) keeps that kind."""


def kinds_of(entry: str | tuple[str, ...]) -> tuple[str, ...]:
    return (entry,) if isinstance(entry, str) else entry
