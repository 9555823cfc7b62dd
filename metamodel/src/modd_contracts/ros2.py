"""The ROS 2 message ``modd_msgs/msg/Window`` (``messages/Window.msg``): one
source for the generators (the integrator's ``modd_msgs`` package) and the
ROS 2 bridge (``modd.ros2.messages``, which hashes and serialises it).

>>> "float64 value" in window_msg()
True
"""

from __future__ import annotations

from importlib.resources import files


def window_msg() -> str:
    """The text of ``modd_msgs/msg/Window.msg``."""
    return (files("modd_contracts") / "messages" / "Window.msg").read_text(encoding="utf-8")
