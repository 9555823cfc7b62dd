"""The MAVLink bridge (``modd-mavlink``): reads an autopilot, publishes the
fields the model's ``kind mavlink`` sensors map to the PubBroker (docs/mavlink.md).

Modules: ``dialect`` (the pymavlink message set), ``mapping`` (model → field
mappings and message intervals), ``decode`` (bytes → frames, never raises),
``autopilot`` (HEARTBEAT, lost/back, reboots, rate requests), ``transport``
(UDP or serial), ``status`` (counters), ``bridge`` (the loop), ``cli``."""
