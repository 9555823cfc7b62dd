"""The REJECT reason codes come from the wire contract (wire.json, RejectReason),
as the PubBroker's; every code has the sentence a publisher's user reads."""

from __future__ import annotations

from modd.ingress import REASONS, Reject
from modd_contracts.ingress_wire_gen import RejectReason


def test_every_reason_of_the_contract_has_its_sentence() -> None:
    assert set(REASONS) == set(RejectReason)


def test_a_code_outside_the_contract_is_shown_by_its_number() -> None:
    assert Reject(0, len(RejectReason), 1, "").reason_text == f"reason {len(RejectReason)}"
