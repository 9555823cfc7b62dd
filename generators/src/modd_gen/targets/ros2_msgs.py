"""The ROS 2 message package ``modd_msgs`` (``msg/Window.msg``,
``package.xml``, ``CMakeLists.txt``) for the integrator, so that ROS 2 nodes
can read what ``modd-ros2`` publishes (docs/ecosystem.md). The package is the
same for every model; ``Window.msg`` is the one source of the message (the
bridge reads it too, :func:`modd_contracts.ros2.window_msg`)."""

from __future__ import annotations

from modd_contracts.ros2 import window_msg

from ..artifact import Artifact
from ..context import Context
from ..render import render

ROOT = "integrator/ros2/modd_msgs"
VERSION = "0.1.0"


def artifacts(ctx: Context) -> list[Artifact]:
    del ctx  # the package does not depend on the model
    return [
        Artifact(f"{ROOT}/msg/Window.msg", window_msg(), "integrator"),
        Artifact(
            f"{ROOT}/package.xml", render("ros2/package.xml.j2", version=VERSION), "integrator"
        ),
        Artifact(f"{ROOT}/CMakeLists.txt", render("ros2/CMakeLists.txt.j2"), "integrator"),
    ]
