"""The window record across config epochs (modd.subbroker.window_record): the gaps of a
subscriber over several configs (SubBroker restart, PubBroker restart, redeploy), each on
its own epoch's grid, against an independent count window by window; and the record kept
in the state directory reads back the same."""

from __future__ import annotations

import json
import random
import time
from fractions import Fraction
from pathlib import Path
from types import SimpleNamespace

import pytest
from modd.subbroker.fanout import FanOut
from modd.subbroker.record_file import read_record
from modd.subbroker.window_record import Due, Epoch, WindowRecord
from modd_plan.streams import Source, StreamKey

S = 1_000_000_000
T0 = 1_700_000_000 * S
FAST = StreamKey("usv.a.x", "MIN", Fraction(1, 4))
SLOW = StreamKey("usv.a.x", "MIN", Fraction(2))
OTHER = StreamKey("usv.b.y", "AVERAGE", Fraction(1, 2))


def three_epochs() -> WindowRecord:
    rec = WindowRecord()
    # config 1 from T0: sub derived MIN/2 s from MIN/0.25 s; config 2 (a SubBroker restart,
    # epoch not on config 1's grid) the same; config 3 (a redeploy) asks OTHER instead
    rec.begin(Epoch("m", 1, T0, [Due("sub", SLOW, FAST, "m", "float32")]))
    rec.begin(Epoch("m", 2, T0 + 60 * S + 123_456, [Due("sub", SLOW, FAST, "m", "float32")]))
    rec.begin(
        Epoch(
            "m",
            3,
            T0 + 120 * S + 77,
            [Due("sub", OTHER, OTHER, "K", "float64"), Due("other", FAST, FAST, "m", "float32")],
        )
    )
    return rec


def windows(epoch: int, period: int, lo: int, hi: int) -> set[int]:
    return {s for s in range(epoch, hi, period) if s >= lo and s + period <= hi}


def test_gaps_span_every_epoch_on_its_own_grid() -> None:
    rec = three_epochs()
    rng = random.Random(7)
    got_live: set[tuple[StreamKey, int, int]] = set()
    for e, (stream, until) in zip(
        rec.epochs, [(FAST, T0 + 60 * S), (FAST, T0 + 120 * S), (OTHER, T0 + 200 * S)], strict=True
    ):
        q = int(stream.period * S)
        fan = FanOut([stream])  # what the SubBroker delivers, derived windows included
        for d in (d for d in e.due if d.source == stream):
            fan.route(d.stream, () if d.stream == d.source else (Source(FAST, 8),), d.subscriber)
        for s in sorted(windows(e.epoch_ns, q, e.epoch_ns, until)):
            if rng.random() < 0.7:  # the link delivered 70 % of the live windows
                rec.add_received(stream, s, s + q)
                got_live.add((stream, s, s + q))
                for out in fan.on_slot(0, (s + q - e.epoch_ns) // 1000, {0: 1.0}):
                    if out.stream != stream:
                        end = e.epoch_ns + out.end_us * 1000
                        rec.add_derived(out.stream, end - 2 * S, end)
    lo, hi = T0 + 10 * S, T0 + 190 * S
    runs = rec.gaps("sub", lo, hi)
    asked = {
        (r.stream, r.from_ns + k * int(r.stream.period * S), r.config_id)
        for r in runs
        for k in range(r.windows)
    }
    # independently: every window due in [lo, hi) whose source windows did not all arrive
    want = set()
    for e, end in zip(
        rec.epochs, [rec.epochs[1].epoch_ns, rec.epochs[2].epoch_ns, hi], strict=True
    ):
        (due,) = [d for d in e.due if d.subscriber == "sub"]
        q, qs = int(due.stream.period * S), int(due.source.period * S)
        for s in windows(e.epoch_ns, q, max(lo, e.epoch_ns), min(end, hi)):
            if not all((due.source, t, t + qs) in got_live for t in range(s, s + q, qs)):
                want.add((due.stream, s, e.config_id))
    assert asked == want and len(want) > 50
    assert {c for _, _, c in asked} == {1, 2, 3}  # earlier configs' windows too
    assert all(r.value_type == ("float64" if r.stream == OTHER else "float32") for r in runs)


def test_backfilled_windows_are_not_asked_again() -> None:
    rec = three_epochs()
    (first, *_) = rec.gaps("sub", T0, T0 + 30 * S)
    rec.add_filled("sub", first.stream, first.from_ns, first.from_ns + first.windows * 2 * S)
    assert first not in rec.gaps("sub", T0, T0 + 30 * S)
    assert rec.gaps("sub", T0, T0 + 30 * S) == []


def test_kept_record_reads_back_the_same() -> None:
    rec = three_epochs()
    rec.add_received(FAST, T0, T0 + 10 * S)
    rec.add_received(FAST, T0 + 20 * S, T0 + 30 * S)
    rec.add_filled("sub", SLOW, T0 + 10 * S, T0 + 12 * S)
    back = read_record(json.loads(json.dumps(rec.to_json())))
    assert back.to_json() == rec.to_json()
    assert back.gaps("sub", T0, T0 + 200 * S) == rec.gaps("sub", T0, T0 + 200 * S)
    assert back.received_until() == T0 + 30 * S


@pytest.mark.parametrize(
    "doc",
    [
        {},
        {"epochs": [{"mission": "m"}]},
        {"epochs": [], "received": {"usv.a.x/MIN/0.25": [[5, 1]]}, "filled": []},
        {"epochs": [], "received": {"nonsense": []}, "filled": []},
    ],
)
def test_a_damaged_record_is_refused(doc: object) -> None:
    with pytest.raises((KeyError, TypeError, ValueError)):
        read_record(doc)


def test_the_mission_starts_at_its_first_epoch_and_names_its_subscribers() -> None:
    rec = three_epochs()
    rec.begin(Epoch("older", 9, T0 - 100 * S, [Due("gone", FAST, FAST, "m", "float32")]))
    assert rec.mission_start("m") == T0
    assert rec.subscribers(T0) == {"sub", "other"}
    assert rec.subscribers(T0 + 130 * S) == {"sub", "other"}
    rec.begin(Epoch("m2", 4, T0 + 300 * S, []))
    assert rec.mission_start("m") is None and rec.mission_start("m2") == T0 + 300 * S


def fast_running() -> SimpleNamespace:
    """What the manager reads of a running config: sub due FAST from T0 (config 1)."""
    ps = SimpleNamespace(stream=FAST, sources=(), subscribers=["sub"])
    return SimpleNamespace(
        plan=SimpleNamespace(streams=[ps]),
        model={"name": "m"},
        topic_info={FAST.topic: ("m", "float32")},
        config=SimpleNamespace(config_id=1),
        epoch_ns=T0,
        fanout=SimpleNamespace(sent=[FAST]),
    )


def test_the_manager_keeps_the_record_without_a_clean_stop(tmp_path: Path) -> None:
    """Written within SAVE_S of a live window (a kill -9 loses at most that), read back by
    the next SubBroker: the earlier epoch's gaps are still known."""
    from modd.link.frames import Value
    from modd.link.receiver import Window
    from modd.subbroker.backfill import SAVE_S, BackfillManager
    from modd.subbroker.kept import StateDir

    running = fast_running()
    m = BackfillManager(lambda _f: None, lambda: [], StateDir(tmp_path))
    m.on_config(running)  # type: ignore[arg-type]
    q = S // 4
    windows = [
        Window(1, k, 0, T0 + k * q, T0 + (k + 1) * q, Value(True, 1.0))
        for k in range(40)
        if not 10 <= k < 20
    ]
    m.on_windows(running, windows)  # type: ignore[arg-type]
    deadline = time.monotonic() + SAVE_S + 5
    while True:  # no close(): as after a kill -9
        doc = StateDir(tmp_path).load_windows()
        if doc and doc["received"]:
            break
        assert time.monotonic() < deadline, "the record was not written"
        time.sleep(0.05)
    again = BackfillManager(lambda _f: None, lambda: [], StateDir(tmp_path))
    assert again.received_until() == T0 + 40 * q
    assert [
        (r.from_ns, r.windows, r.config_id) for r in again.record.gaps("sub", T0, T0 + 10 * S)
    ] == [(T0 + 10 * q, 10, 1)]
    m.close()


def test_a_derived_window_counts_when_delivered_not_when_its_source_arrived() -> None:
    """The lossy radio's fault: the 2 s window's source interval arrived, but the
    fan-out did not deliver it: it is a gap (was: counted delivered, never backfilled)."""
    rec = WindowRecord()
    rec.begin(Epoch("m", 1, T0, [Due("sub", SLOW, FAST, "m", "float32")]))
    rec.add_received(FAST, T0, T0 + 6 * S)
    rec.add_derived(SLOW, T0, T0 + 2 * S)
    rec.add_derived(SLOW, T0 + 4 * S, T0 + 6 * S)
    (run,) = rec.gaps("sub", T0, T0 + 6 * S)
    assert (run.from_ns, run.windows, run.stream) == (T0 + 2 * S, 1, SLOW)
    back = read_record(json.loads(json.dumps(rec.to_json())))
    assert back.gaps("sub", T0, T0 + 6 * S) == [run]


def test_a_record_of_an_earlier_version_counts_derived_windows_by_their_source() -> None:
    rec = three_epochs()
    rec.add_received(FAST, T0, T0 + 10 * S)
    doc = rec.to_json()
    del doc["derived"]
    back = read_record(doc)
    assert back.gaps("sub", T0, T0 + 10 * S) == []


def test_the_derived_window_the_link_came_back_in_is_a_gap_at_once() -> None:
    """Fill gaps asked just after the link came back (issue 42's rehearsal): the 2 s
    window under way then lost its first source windows in the outage, so the fan-out
    never delivers it; it is asked for with the outage's windows (was: left out, as
    ending after the last live window, and missing on the chart after the fill). A
    direct window under way, or a derived one whose sources all came, is not."""
    rec = WindowRecord()
    rec.begin(
        Epoch(
            "m",
            1,
            T0,
            [Due("sub", SLOW, FAST, "m", "float32"), Due("fast", FAST, FAST, "m", "float32")],
        )
    )
    rec.add_received(FAST, T0, T0 + 3 * S)  # the outage: 3 s .. 8.5 s
    rec.add_derived(SLOW, T0, T0 + 2 * S)
    rec.add_received(FAST, T0 + 8 * S + S // 2, T0 + 9 * S + S // 4)
    until = T0 + 9 * S + S // 4
    runs = rec.gaps("sub", T0, until)
    # 2..8 s, then 8..10 s (under way) as a run of its own, last: the drone sends it once its
    # archive holds its end, and it must hold up no other run meanwhile
    assert [(r.from_ns, r.windows) for r in runs] == [(T0 + 2 * S, 3), (T0 + 8 * S, 1)]
    rec.add_filled("sub", SLOW, T0 + 8 * S, T0 + 10 * S)  # filled: not asked again
    assert [(r.from_ns, r.windows) for r in rec.gaps("sub", T0, until)] == [(T0 + 2 * S, 3)]
    # the fast stream's windows: the outage's alone (from 8.5 s, live)
    (fast,) = rec.gaps("fast", T0, until)
    assert (fast.from_ns, fast.windows) == (T0 + 3 * S, 22)
    # no outage inside the window under way: the live path completes it
    rec.add_received(FAST, T0 + 3 * S, T0 + 8 * S + S // 2)
    rec.add_derived(SLOW, T0 + 2 * S, T0 + 8 * S)
    assert rec.gaps("sub", T0, until) == []


def test_windows_delivered_just_before_a_kill_are_kept_by_the_journal(tmp_path: Path) -> None:
    """Issue 44's wire duplicates: windows delivered (live and backfilled) after the
    record's last save, then a kill -9 (no close, no save): the next SubBroker knows
    them from the journal, so none is a gap (none backfilled twice). A line cut by the
    kill is skipped; a save sets the journal aside and removes it once written."""
    from modd.link.frames import Value
    from modd.link.receiver import Window
    from modd.subbroker.backfill import BackfillManager
    from modd.subbroker.kept import StateDir

    running = fast_running()
    q = S // 4

    def live(ks: range) -> list[Window]:
        return [Window(1, k, 0, T0 + k * q, T0 + (k + 1) * q, Value(True, 1.0)) for k in ks]

    m = BackfillManager(lambda _f: None, lambda: [], StateDir(tmp_path))
    m.on_config(running)  # type: ignore[arg-type]
    # on_config saved the record: the epoch only
    m.journal_live(running, live(range(0, 10)))  # type: ignore[arg-type]
    m.journal_live(running, live(range(20, 30)))  # type: ignore[arg-type]
    assert m._journal is not None
    m._journal.append([["f", "sub", FAST.key, T0 + 10 * q, T0 + 12 * q]])
    with open(tmp_path / "windows.journal", "ab") as f:
        f.write(b'[["r","usv.a.x/MIN/0.25",')  # the kill cut this line
    again = BackfillManager(lambda _f: None, lambda: [], StateDir(tmp_path))
    gaps = [(r.from_ns, r.windows) for r in again.record.gaps("sub", T0, T0 + 30 * q)]
    assert gaps == [(T0 + 12 * q, 8)], gaps
    again._dirty = True
    again.save()  # the record now holds the journal: set aside, then removed
    assert not (tmp_path / "windows.journal.old").exists()
    third = BackfillManager(lambda _f: None, lambda: [], StateDir(tmp_path))
    assert [(r.from_ns, r.windows) for r in third.record.gaps("sub", T0, T0 + 30 * q)] == gaps
    for mgr in (m, again, third):
        mgr.close()


def test_a_save_between_the_journal_and_the_put_keeps_the_window(tmp_path: Path) -> None:
    """The clock thread's save may come between a window's journal line and its put
    (then a kill -9, before the next save): the record it writes holds the window, or
    the journal it keeps does. (Seen in the namespace radio test: a window delivered
    live was in neither, and the restarted station backfilled it.)"""
    from modd.link.frames import Value
    from modd.link.receiver import Window
    from modd.subbroker.backfill import BackfillManager
    from modd.subbroker.kept import StateDir

    running = fast_running()
    q = S // 4
    live = [Window(1, k, 0, T0 + k * q, T0 + (k + 1) * q, Value(True, 1.0)) for k in range(8)]
    m = BackfillManager(lambda _f: None, lambda: [], StateDir(tmp_path))
    m.on_config(running)  # type: ignore[arg-type]
    m.on_windows(running, live[:4])  # type: ignore[arg-type]
    m.journal_live(running, live[4:])  # type: ignore[arg-type]  # their put is under way
    m.save()  # the clock thread's save
    again = BackfillManager(lambda _f: None, lambda: [], StateDir(tmp_path))  # after kill -9
    assert again.record.gaps("sub", T0, T0 + 8 * q) == []
    for mgr in (m, again):
        mgr.close()


def test_a_journal_that_cannot_be_opened_is_said_and_the_run_goes_on(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    from modd.subbroker.backfill import BackfillManager
    from modd.subbroker.kept import StateDir

    blocked = tmp_path / "state"
    blocked.mkdir()
    (blocked / "windows.journal").mkdir()  # not a file: it cannot be opened for appending
    m = BackfillManager(lambda _f: None, lambda: [], StateDir(blocked))
    assert m._journal is None
    assert "cannot keep the window journal" in caplog.text
    m.close()
