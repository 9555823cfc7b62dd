"""Per publisher, a C++ driver project that builds with only a compiler and
CMake: the MoDD publisher client is carried inside.

Generated (rewritten on every run): CMakeLists.txt, README.md, the client,
``generated/<publisher>_topics.hpp`` and the cross-compile toolchain file.
User-owned (written once): ``src/driver.cpp`` (a read function per topic, where
the integrator's code goes, and the main loop with one publish call per topic)
and ``user.cmake`` (additions to the build).

Topics of plug-and-play sensors get no read function: the MAVLink bridge
(``modd-mavlink``, docs/mavlink.md) publishes the autopilot's (``kind
mavlink``), ``modd-sensors`` (docs/sensors.md) the NMEA, ASCII and Modbus
instruments' (``kind nmea``, ``ascii``, ``modbus``), as the model maps them.
A publisher of such topics only gets no driver at all; a model with
instruments gets ``integrator/PLUG-AND-PLAY.md`` saying which sensors need no
driver (and, when none does, that there is nothing to write)."""

from __future__ import annotations

from ..artifact import Artifact, Ownership
from ..context import Context, PublisherView
from ..cpp_client import client, read
from ..render import BANNER, render


def client_sources() -> tuple[str, str]:
    """The C++ publisher client, carried into every driver project (package data)."""
    return client("publisher")


def _project(ctx: Context, pub: PublisherView) -> list[Artifact]:
    root = f"integrator/{pub.name}-driver"
    header, source = client_sources()
    args = {
        "pub": pub,
        "drone": ctx.drone,
        "ingress": ctx.ingress,
        "archive_dir": ctx.model["pubBroker"]["logPath"],
    }
    gen = [
        ("CMakeLists.txt", "cpp_driver/CMakeLists.txt.j2"),
        ("README.md", "cpp_driver/README.md.j2"),
        (f"generated/{pub.name}_topics.hpp", "cpp_driver/topics.hpp.j2"),
    ]
    out = [Artifact(f"{root}/{path}", render(tpl, **args), "integrator") for path, tpl in gen]
    # the cross toolchain the runtime itself is built with (runtime/cpp/cmake), carried
    toolchain = f"# {BANNER}\n" + read("aarch64-linux-gnu.cmake")
    out.append(Artifact(f"{root}/cmake/aarch64-linux-gnu.cmake", toolchain, "integrator"))
    out += [
        Artifact(f"{root}/modd/include/modd/client/publisher.hpp", header, "integrator"),
        Artifact(f"{root}/modd/src/publisher.cpp", source, "integrator"),
        # the ingress wire header the client shares with the PubBroker
        Artifact(f"{root}/modd/include/modd/ingress/wire.hpp", read("wire.hpp"), "integrator"),
        Artifact(
            f"{root}/modd/include/modd/ingress/wire.gen.hpp", read("wire.gen.hpp"), "integrator"
        ),
    ]
    user = [
        ("src/driver.cpp", "cpp_driver/driver.cpp.j2"),
        ("user.cmake", "cpp_driver/user.cmake.j2"),
    ]
    out += [
        Artifact(f"{root}/{path}", render(tpl, **args), "integrator", Ownership.USER)
        for path, tpl in user
    ]
    return out


def _python(ctx: Context, pub: PublisherView) -> Artifact:
    """The same driver in Python, on the Python publisher client (user-owned)."""
    text = render("py_publisher/publisher.py.j2", pub=pub, drone=ctx.drone, ingress=ctx.ingress)
    return Artifact(
        f"integrator/python/{pub.name}.py", text, "integrator", Ownership.USER, executable=True
    )


_READER = {
    "mavlink": "modd-mavlink",
    "nmea": "modd-sensors",
    "ascii": "modd-sensors",
    "modbus": "modd-sensors",
}


def _driven(ctx: Context) -> list[PublisherView]:
    """The publishers with their topics that a driver reads (not a plug-and-play reader)."""
    bridged = {
        s["name"] for s in ctx.model["drone"]["sensors"] if s.get("kind", "generic") in _READER
    }
    views = [
        PublisherView(p.name, p.period_s, [t for t in p.topics if t.sensor not in bridged])
        for p in ctx.publishers
    ]
    return [v for v in views if v.topics]


def _plug_and_play(ctx: Context, driven: list[PublisherView]) -> list[Artifact]:
    """The note on the sensors no driver reads, for a model with instruments."""
    sensors = ctx.model["drone"]["sensors"]
    if not any(s.get("kind") in ("nmea", "ascii", "modbus") for s in sensors):
        return []
    rows = [
        {
            "name": s["name"],
            "kind": s["kind"],
            "reader": _READER[s["kind"]],
            "device": s.get("device", {}).get("path", "(the bridge's --connect)"),
        }
        for s in sensors
        if s.get("kind", "generic") in _READER
    ]
    text = render("cpp_driver/plug_and_play.md.j2", drone=ctx.drone, sensors=rows, driven=driven)
    return [Artifact("integrator/PLUG-AND-PLAY.md", text, "integrator")]


def artifacts(ctx: Context) -> list[Artifact]:
    driven = _driven(ctx)
    return [a for pub in driven for a in [*_project(ctx, pub), _python(ctx, pub)]] + _plug_and_play(
        ctx, driven
    )
