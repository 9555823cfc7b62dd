"""Pairing a drone with its base station (docs/operations.md, "Pair"): the
workbench seals a bundle for one drone (:mod:`.bundle`), the drone opens it
with the one-time code shown to the operator and writes its configuration
(:mod:`.install`, ``modd-pair`` / ``modd pair``: :mod:`.cli`)."""
