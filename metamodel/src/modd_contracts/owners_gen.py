"""Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.

The role owning each model part (metamodel/modd.schema.json ``x-owner``;
``None``: any editor), by JSON pointer.
"""

from __future__ import annotations

MODEL_PART_OWNERS: dict[str, str | None] = {
    "/schemaVersion": "designer",
    "/drone": "designer",
    "/drone/sensors": "integrator",
    "/pubBroker": "designer",
    "/subBroker": "designer",
    "/link": "designer",
    "/publishers": "designer",
    "/subscribers": "scientist",
    "/campaign": "designer",
    "/layout": None,
}
