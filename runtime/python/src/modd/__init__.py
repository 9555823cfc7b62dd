"""MoDD runtime for Python: the link codec, publisher and subscriber clients and the SubBroker.

>>> import modd
>>> for sample in modd.subscribe("usv", "sub_1"):   # doctest: +SKIP
...     print(sample.value)
"""

from __future__ import annotations

from typing import Any


def subscribe(*args: Any, **kwargs: Any) -> Any:
    """:func:`modd.subscriber.subscribe` (imported on first use, so that
    ``import modd`` stays cheap)."""
    from .subscriber import subscribe as _subscribe

    return _subscribe(*args, **kwargs)
