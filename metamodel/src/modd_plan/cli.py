"""``modd plan FILE [--json] [--calibrate ARCHIVE]``: the plan of a model,
for people or programs.

Registered through the ``modd.commands`` entry point ``plan``. An archive is
read by the reader registered in the ``modd.samples`` entry-point group (the
runtime's ``mcap``): the metamodel does not import the runtime.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable, Sequence
from fractions import Fraction
from functools import lru_cache
from pathlib import Path
from typing import Any, TextIO

from modd_model.io import load_file, locate
from modd_model.numbers import fraction_to_decimal, to_fraction
from modd_model.query import topics

from .calibration import Calibration, CalibrationError, Series
from .campaign import plan_campaign
from .linkbudget import budget_lines
from .plan import METHODS, Plan, PlanningError, make_plan
from .proposals import Proposal
from .radio import RadioReport

#: Slots printed in the human-readable schedule.
TEXT_SLOT_LIMIT = 40


def _decimal(text: str) -> Fraction:
    try:
        return to_fraction(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def _status_period(text: str) -> int:
    """A STATUS period in whole seconds, 0 (none) to a day."""
    from modd_contracts.link_wire_gen import MAX_STATUS_PERIOD_S

    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number of seconds: {text!r}") from None
    if not 0 <= value <= MAX_STATUS_PERIOD_S:
        raise argparse.ArgumentTypeError(f"{value} s: from 0 (no STATUS) to {MAX_STATUS_PERIOD_S}")
    return value


def _positive_int(text: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return int(text)


def register(subparsers: Any) -> None:
    """Add ``plan`` to the ``modd`` command line."""
    p = subparsers.add_parser(
        "plan", help="schedule, buffer sizes, delays and link cost of a model"
    )
    p.add_argument("file", metavar="FILE", help=".modd or .json model")
    p.add_argument("--json", action="store_true", help="print the plan as one JSON object")
    p.add_argument("--ping", type=_decimal, metavar="S", help="PING_TIME in seconds")
    p.add_argument("--alpha", type=_decimal, help="weight of the sum of deviations")
    p.add_argument("--beta", type=_decimal, help="weight of the largest deviation")
    p.add_argument("--max-buffer", type=_positive_int, metavar="N", help="MAX_BUFFER")
    p.add_argument("--method", choices=METHODS, default="exact", help="buffer-size solver")
    p.add_argument(
        "--status-period",
        type=_status_period,
        metavar="S",
        help="the PubBroker's STATUS period the SubBroker asks for "
        "(its pubbroker_status_period_s; default 60, 0: none), in the control traffic",
    )
    p.add_argument(
        "--calibrate",
        metavar="ARCHIVE",
        help="size quantised values from the samples of an archive (.mcap) of a test flight",
    )
    p.set_defaults(func=run_plan)


#: The entry-point group of archive readers: ``name = "module:function"``,
#: ``function(path, topics) -> {topic: (stamps_ns, values)}``.
SAMPLES_GROUP = "modd.samples"


def load_calibration(archive: str, topics: list[str]) -> Calibration:
    """The archive's samples of ``topics`` as a calibration; a
    :class:`CalibrationError` when no reader is installed, the archive cannot
    be read, or it holds none of the topics."""
    from importlib.metadata import entry_points

    readers = {ep.name: ep for ep in entry_points(group=SAMPLES_GROUP)}
    if not readers:
        raise CalibrationError(
            f"{archive}: no archive reader is installed (entry-point group {SAMPLES_GROUP!r}); "
            "install the runtime (package modd-runtime) to calibrate from an archive"
        )
    reader = (readers.get("mcap") or next(iter(readers.values()))).load()
    path = Path(archive)
    if not path.is_file():
        raise CalibrationError(f"{archive}: no such archive")
    st = path.stat()
    state = (st.st_ino, st.st_size, st.st_mtime_ns)
    series = _read(reader, str(path.resolve()), state, tuple(sorted(topics)))
    if not series:
        raise CalibrationError(
            f"{archive}: holds no sample of the model's topics ({', '.join(topics)})"
        )
    return Calibration(path.name, series)


@lru_cache(maxsize=2)
def _read(
    reader: Callable[[Path, list[str]], dict[str, Series]],
    path: str,
    state: tuple[int, int, int],
    topics: tuple[str, ...],
) -> dict[str, Series]:
    """An archive's samples, read once while the file stays as it is: the live
    plan of the workbench re-plans with the same archive at every edit.
    ``state`` (inode, size, modification time) is only the cache's key: an
    archive still being written, or replaced, is read again."""
    del state
    return reader(Path(path), list(topics))


def run_plan(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """Load, plan, print. Exit 0 when feasible, 1 on a bad model or archive, 3 when the
    plan violates the 3 x PING cap, 4 when it exceeds the link's byte budget,
    5 when its radio refuses it (over the duty-cycle limit; the plan and the
    nearest plans that fit are still printed), 6 when a campaign's shared
    channel cannot carry its vehicles together."""
    out = out or sys.stdout
    result = load_file(args.file)
    if not result.ok or result.model is None:
        for d in result.diagnostics:
            print(d, file=sys.stderr)
        return 1
    calibration = None
    archive = getattr(args, "calibrate", None)  # callers may build the namespace themselves
    if archive is not None:
        try:
            calibration = load_calibration(archive, list(topics(result.model)))
        except CalibrationError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
    if "campaign" in result.model:
        return _run_campaign(args, result.model, calibration, out)
    try:
        plan = make_plan(result.model, **_options(args, calibration))
    except PlanningError as exc:
        for d in locate(exc.diagnostics, result, args.file):
            print(d, file=sys.stderr)
        return 1
    if args.json:
        _dump(plan.to_json(), out)
    else:
        out.write(render_text(plan))
    return _exit_code(plan)


def _options(args: argparse.Namespace, calibration: Calibration | None) -> dict[str, Any]:
    """make_plan's options from the command line."""
    return {
        "ping_s": args.ping,
        "alpha": args.alpha,
        "beta": args.beta,
        "max_buffer": args.max_buffer,
        "method": args.method,
        "calibration": calibration,
        "status_period_s": getattr(args, "status_period", None),
    }


def _dump(doc: Any, out: TextIO) -> None:
    json.dump(doc, out, indent=2)
    out.write("\n")


def _run_campaign(
    args: argparse.Namespace, model: dict[str, Any], calibration: Calibration | None, out: TextIO
) -> int:
    """A campaign: one plan per drone, then each shared channel's load."""
    try:
        result = plan_campaign(model, **_options(args, calibration))
    except PlanningError as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        return 1
    if args.json:
        _dump(result.to_json(), out)
    else:
        for name, plan in result.plans.items():
            out.write(f"== drone {name}\n{render_text(plan)}")
        for load in result.channels:
            rate = f" of {load.rate_bps} B/s" if load.rate_bps is not None else ""
            out.write(f"== channel {load.name} ({', '.join(load.vehicles)}): ")
            out.write(f"{load.bytes_per_s:.1f} B/s{rate}\n")
            for error in load.errors:
                out.write(f"error: {error}\n")
    worst = max((_exit_code(p) for p in result.plans.values()), default=0)
    return worst or (0 if result.fits else 6)


def _exit_code(plan: Plan) -> int:
    if plan.buffers.infeasible:
        return 3
    if plan.budget is not None and plan.budget.error:
        return 4
    return 5 if plan.radio is not None and not plan.radio.fits else 0


def _sec(value: Fraction) -> str:
    return fraction_to_decimal(value) + " s"


def render_text(plan: Plan) -> str:
    """The plan for a person: schedule, buffers, delays, link cost."""
    j = plan.to_json()
    sched = plan.schedule
    lines = [
        f"hyperperiod {j['hyperperiod_s']} s, {j['messages_per_hyperperiod']} messages per "
        "hyperperiod",
        "",
        "sent streams:",
    ]
    lines += [f"  [{s.id}] {s.stream.key}" for s in plan.sent_streams]
    derived = [s for s in plan.streams if not s.sent]
    if derived:
        lines.append("derived at the SubBroker:")
        lines += [
            f"  {s.stream.key} <- " + " + ".join(f"{x.factor} x {x.stream.key}" for x in s.sources)
            for s in derived
        ]
    lines += ["", "schedule (date -> streams):"]
    keys = {s.id: s.stream.key for s in plan.sent_streams}
    for _, date, ids in sched.first_slots(TEXT_SLOT_LIMIT):
        lines.append(f"  {_sec(date):>12} -> " + ", ".join(keys[i] for i in ids))
    if sched.messages_per_hyperperiod > TEXT_SLOT_LIMIT:
        lines.append(f"  ... ({sched.messages_per_hyperperiod - TEXT_SLOT_LIMIT} more)")
    lines += ["", "buffer sizes:"]
    lines += [f"  {t}: {n}" for t, n in plan.buffer_sizes.items()]
    lines += ["", "delays (|ps - n x pm|):"]
    lines += [f"  {name}: {_sec(d)}" for name, d in plan.delays.items()]
    link = j["predicted_link_bytes_per_s"]
    lines += [
        "",
        f"link: {link['drone_to_base']} B/s drone->base, {link['base_to_drone']} B/s "
        "base->drone (IP+TCP included)",
        f"plain pub/sub: {link['plain_pubsub']} B/s (+ {link['plain_pubsub_acks']} B/s ACKs); "
        f"saving {100 * link['saving_ratio']:.1f} %",
    ]
    if plan.budget is not None:
        lines += budget_lines(plan.budget)
    if plan.radio is not None:
        lines += _radio_lines(plan.radio, plan.proposals)
    lines += _infeasible_lines(plan)
    return "\n".join(lines) + "\n"


def _infeasible_lines(plan: Plan) -> list[str]:
    if not plan.infeasible:
        return []
    cap = _sec(Fraction(plan.constants.cap_us, 1_000_000))
    lines = [
        "",
        f"INFEASIBLE: the delay cap 3 x PING = {cap} cannot be met; "
        "the plan above lifts it for these topics only:",
    ]
    lines += [f"  {x.topic} ({', '.join(x.subscribers)}): {x.reason}" for x in plan.infeasible]
    return lines


def _radio_lines(report: RadioReport, proposals: Sequence[Proposal]) -> list[str]:
    """The radio's figures for a person (``modd plan``'s text output)."""
    p = report.profile
    lines = [
        "",
        f"radio ({p.kind}): {report.bytes_per_s:.1f} B/s, "
        f"{report.packets_per_hour:.0f} packets/h, air time {report.at_most}"
        f"{report.air_s_per_hour:.1f} s/h, energy {report.at_most}"
        f"{report.energy_j_per_hour:.1f} J/h",
    ]
    if report.ceiling:
        c = report.ceiling
        why = (
            "every delta at its variable's declared range, " if report.upper_bound is False else ""
        )
        lines.append(
            f"  at most {c.air_s_per_hour:.1f} s/h and {c.energy_j_per_hour:.1f} J/h "
            f"({why}a STATUS of the whole STATUS room: the duty-cycle check's)"
        )
    if report.control_s_per_hour:
        lines.append(f"  of which the link's control traffic {report.control_s_per_hour:.1f} s/h")
    lines += _calibration_lines(report)
    share = report.duty_share
    if share is not None:
        lines.append(
            f"  {100 * share:.1f} % of the {100 * (p.duty_cycle or 0):g} % duty-cycle limit"
        )
    battery = report.battery_share
    if battery is not None:
        lines.append(
            f"  {100 * battery:.3f} % of the declared {p.battery_wh:g} Wh battery per hour"
        )
    if report.error:
        lines += ["", f"REFUSED BY THE RADIO: {report.error}"]
        lines.append("nearest plans that fit:" if proposals else "no nearer plan fits")
        lines += [
            f"  {q.describe()}: delay {q.max_delay_s:.3f} s, "
            f"{q.report.bytes_per_s:.1f} B/s, air time {q.report.at_most}"
            f"{q.report.air_s_per_hour:.1f} s/h "
            f"({100 * (q.report.duty_share or 0):.0f} %), "
            f"{q.report.energy_j_per_hour:.1f} J/h"
            for q in proposals
        ]
    return lines


def _calibration_lines(report: RadioReport) -> list[str]:
    use = report.calibration
    if use is None:
        return []
    lines = [
        f"  calibrated from {use.source} (first {use.limit} windows of each stream): "
        "mean bytes of an absolute value / a delta"
    ]
    lines += [
        f"    {key}: {float(v.absolute):.2f} / {float(v.delta):.2f} ({v.windows} windows)"
        for key, v in use.sizes
    ]
    if use.missing:
        lines.append(
            "  not calibrated (no sample in the archive; sized as without it): "
            + ", ".join(use.missing)
        )
    return lines
