"""Reading the JSON object of a query to one of the SubBroker's queryables
(deploy, subscribe, backfill), bounded before it is parsed: only the
``backend`` identity may ask (docs/security.md, "Zenoh"), but a stolen
credential must not make the SubBroker parse a 20 MB or 100,000-deep
document (the parser's recursion answered "internal error" and logged a
traceback per query).

>>> read_request(b'{"action": "list"}', 64)
({'action': 'list'}, None)
>>> read_request(b'[[[]]]', 64)[1]
'the request must be a JSON object'
"""

from __future__ import annotations

import json
from typing import Any

from modd_model.jsondepth import MAX_DEPTH, json_depth

#: Largest deploy request: a model of the workbench's 4 MiB body, its text
#: escaped inside JSON (at most 6 bytes a character), with room to spare.
MAX_DEPLOY_BYTES = 32 * 1024 * 1024
#: Largest request to the other queryables (a few fields each).
MAX_SMALL_BYTES = 64 * 1024


def read_request(payload: bytes, max_bytes: int) -> tuple[dict[str, Any], None] | tuple[None, str]:
    """``(request, None)``, or ``(None, reason)`` for a payload that is too
    big, nested deeper than MAX_DEPTH, not JSON, or not an object."""
    if len(payload) > max_bytes:
        return None, f"the request is {len(payload)} bytes; at most {max_bytes} are read"
    depth = json_depth(payload)
    if depth > MAX_DEPTH:
        return None, f"the request is nested {depth} levels deep; at most {MAX_DEPTH}"
    try:
        request = json.loads(payload or b"{}")
    except (ValueError, UnicodeDecodeError) as exc:
        return None, f"the request is not JSON: {exc}"
    if not isinstance(request, dict):
        return None, "the request must be a JSON object"
    return request, None
