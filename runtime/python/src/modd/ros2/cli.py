"""``modd-ros2``: MoDD's delivered values as ROS 2 topics over zenoh, for
ROS 2 (Jazzy) nodes using ``rmw_zenoh_cpp`` — no ROS 2 installed here.

    modd-ros2 --modd-connect tcp/127.0.0.1:7447 --ros-connect tcp/127.0.0.1:7448 --drone usv

``--ros-connect`` is the ROS side's zenoh router (``ros2 run rmw_zenoh_cpp
rmw_zenohd``, which listens on 7447 by default: run one of the two on
another port on a shared machine). docs/ecosystem.md.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import threading

from ..shutdown import stop_on_signals
from ..zenoh_session import ZenohSettings, add_viewer_args, client_settings, open_session


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="modd-ros2", description=__doc__.splitlines()[0])
    add_viewer_args(p)
    p.add_argument(
        "--ros-connect",
        metavar="ENDPOINT",
        help="the ROS 2 zenoh router (rmw_zenohd); default: the same session as "
        "--modd-connect (then its access control must let this identity "
        "put ROS 2 keys and liveliness tokens)",
    )
    p.add_argument(
        "--ros-mode",
        choices=("peer", "client"),
        default="peer",
        help="zenoh mode of the ROS side's session (rmw_zenoh's nodes are peers)",
    )
    p.add_argument("--drone", default="*", help="drone name (default: every drone)")
    p.add_argument(
        "--domain-id",
        type=int,
        default=int(os.environ.get("ROS_DOMAIN_ID", "0")),
        help="ROS domain id (default $ROS_DOMAIN_ID or 0)",
    )
    p.add_argument("--node", default="modd_bridge", help="ROS node name")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    from .bridge import Ros2Bridge

    a = parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="modd-ros2: %(message)s")
    try:
        modd = open_session(client_settings(a.modd_connect, a.credentials))
        ros = (
            modd
            if not a.ros_connect or a.ros_connect == a.modd_connect
            else open_session(ZenohSettings(mode=a.ros_mode, connect=(a.ros_connect,)))
        )
    except ValueError as exc:
        print(f"modd-ros2: {exc}", file=sys.stderr)
        return 1
    bridge = Ros2Bridge(modd, ros, a.drone, a.domain_id, a.node).start()
    print(
        f"modd-ros2: node /{a.node} on ROS domain {a.domain_id}: values of "
        f"{bridge.key} as /<drone>/<subscriber> (modd_msgs/msg/Window) and "
        f"/<drone>/<subscriber>/value (std_msgs/msg/Float64)",
        flush=True,
    )
    stop = threading.Event()
    stop_on_signals(stop)
    try:
        stop.wait()
    except KeyboardInterrupt:
        pass
    finally:
        bridge.close()
        if ros is not modd:
            ros.close()  # type: ignore[no-untyped-call]
        modd.close()  # type: ignore[no-untyped-call]
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
