"""Per subscriber, the scientist's stubs: a Python script on the subscriber API
(prints values, or collects them into a pandas DataFrame), and, for a
subscriber with a TCP endpoint, a C++ project on the C++ subscriber client
(a callback per delivered value)."""

from __future__ import annotations

from typing import Any

from .. import py_client
from ..artifact import Artifact, Ownership
from ..context import Context
from ..cpp_client import client, read
from ..render import render


def subscriber_client_sources() -> tuple[str, str]:
    """The C++ subscriber client, carried into subscriber projects (package data)."""
    return client("subscriber")


def delivered_value_header() -> str:
    """The delivered value's field names (generated from the contract), which
    the subscriber client's parser includes."""
    return read("delivered_value.gen.hpp")


def _python(ctx: Context, sub: dict[str, Any]) -> Artifact:
    topic = ctx.topics[sub["topic"]]
    text = render(
        "py_subscriber/subscriber.py.j2", sub=sub, topic=topic, drone=ctx.drone, station=ctx.station
    )
    return Artifact(f"scientist/python/{sub['name']}.py", text, "scientist", executable=True)


def _cpp(ctx: Context, sub: dict[str, Any]) -> list[Artifact]:
    root = f"scientist/cpp/{sub['name']}"
    header, source = subscriber_client_sources()
    args = {"sub": sub, "topic": ctx.topics[sub["topic"]], "drone": ctx.drone}
    return [
        Artifact(
            f"{root}/CMakeLists.txt",
            render("cpp_subscriber/CMakeLists.txt.j2", **args),
            "scientist",
        ),
        Artifact(f"{root}/modd/include/modd/client/subscriber.hpp", header, "scientist"),
        Artifact(
            f"{root}/modd/include/modd/client/delivered_value.gen.hpp",
            delivered_value_header(),
            "scientist",
        ),
        Artifact(f"{root}/modd/src/subscriber.cpp", source, "scientist"),
        Artifact(
            f"{root}/src/main.cpp",
            render("cpp_subscriber/main.cpp.j2", **args),
            "scientist",
            Ownership.USER,
        ),
    ]


def artifacts(ctx: Context) -> list[Artifact]:
    out: list[Artifact] = []
    for sub in ctx.model["subscribers"]:
        out.append(_python(ctx, sub))
        if "endpoint" in sub:
            out += _cpp(ctx, sub)
    if ctx.model["subscribers"]:
        out += [  # the client the stubs import, so that they run without the MoDD runtime
            Artifact(f"scientist/python/{name}", py_client.read(name), "scientist")
            for name in py_client.ORIGINALS
        ]
        out.append(
            Artifact(
                "scientist/README.md",
                render(
                    "py_subscriber/README.md.j2",
                    subs=ctx.model["subscribers"],
                    drone=ctx.drone,
                    station=ctx.station,
                ),
                "scientist",
            )
        )
    return out
