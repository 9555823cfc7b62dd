"""The MoDD planning engine: which streams cross the link, when (the
schedule), with which double-buffer sizes, at what link cost, and which
dynamic subscriptions the current plan can serve.

>>> from modd_model import load_model
>>> from modd_plan import make_plan, check_dynamic
>>> plan = make_plan(load_model("scenario1.modd"))       # doctest: +SKIP
>>> plan.buffer_sizes                                   # doctest: +SKIP
{'usv.accelerometer.accel_x': 28, 'usv.accelerometer.accel_y': 28, 'usv.accelerometer.accel_z': 6}
"""

from .buffers import BufferProblem, BufferSolution, Infeasibility, Subscription, solve_exact
from .derive import aggregate, derive_value, merge
from .dynamic import Accepted, NotAvailable, check_dynamic
from .plan import Plan, PlannerConstants, buffer_problem, constants_for, make_plan
from .schedule import Schedule
from .streams import AGGREGATIONS, PlannedStream, Source, StreamKey

__all__ = [
    "AGGREGATIONS",
    "Accepted",
    "BufferProblem",
    "BufferSolution",
    "Infeasibility",
    "NotAvailable",
    "Plan",
    "PlannedStream",
    "PlannerConstants",
    "Schedule",
    "Source",
    "StreamKey",
    "Subscription",
    "aggregate",
    "buffer_problem",
    "check_dynamic",
    "constants_for",
    "derive_value",
    "make_plan",
    "merge",
    "solve_exact",
]
