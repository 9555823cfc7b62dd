"""ROS 2 out, without ROS 2: MoDD's delivered values published over zenoh
exactly as ``rmw_zenoh_cpp`` (ROS 2 Jazzy, rmw_zenoh 0.2) expects them
(docs/ecosystem.md): :mod:`.typehash` (REP-2016 RIHS01 hashes),
:mod:`.messages` (the message types and their CDR), :mod:`.rmw` (key
expressions, liveliness tokens, attachments), :mod:`.bridge` and :mod:`.cli`
(``modd-ros2``)."""
