"""``modd up`` restarts a process that died, with a backoff, and gives up after
too many restarts (modd.supervise); driven with a fake clock and fake
processes, checked against the policy's numbers worked out by hand."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from modd.supervise import DEFAULT_POLICY, RestartPolicy, Restarts, watch


def test_backoff_doubles_to_its_bound_and_resets_after_a_stable_run() -> None:
    r = Restarts(RestartPolicy(backoff_s=1, backoff_max_s=4, max_restarts=100, window_s=1e9))
    delays = [(r.on_exit("a", t, ran_s=0.5) or 0.0) - t for t in range(0, 60, 10)]
    assert delays == [1, 2, 4, 4, 4, 4]
    assert r.on_exit("a", 100.0, ran_s=61.0) == 101.0  # ran 61 s: from 1 s again
    assert r.on_exit("b", 100.0, ran_s=0.0) == 101.0  # each process its own backoff


def test_it_gives_up_after_max_restarts_within_the_window() -> None:
    r = Restarts(RestartPolicy(max_restarts=3, window_s=100))
    assert all(r.on_exit("a", t, 0.0) is not None for t in (0.0, 10.0, 20.0))
    assert r.on_exit("a", 30.0, 0.0) is None
    assert r.on_exit("a", 105.0, 0.0) is not None  # the first one has left the window


@dataclass
class Fake:
    """A process that dies at the times given (its run's start + lifetime)."""

    name: str
    lifetimes: list[float]
    clock: list[float]
    restartable: bool = True
    log: Path = Path("fake.log")
    starts: list[float] = field(default_factory=list)

    def start(self, env: dict[str, str]) -> None:
        assert env == {"K": "v"}
        self.starts.append(self.clock[0])

    def exit_code(self) -> int | None:
        run = len(self.starts)  # 0: the first run, n: after n restarts
        if run >= len(self.lifetimes):
            return None  # runs for good
        begun = self.starts[-1] if self.starts else 0.0
        return 9 if self.clock[0] - begun >= self.lifetimes[run] else None

    def pid(self) -> int | None:
        return 1000 + len(self.starts)


def run(
    children: list[Fake], clock: list[float], until: float, policy: RestartPolicy = DEFAULT_POLICY
) -> tuple[int, list[str]]:
    said: list[str] = []

    def sleep(s: float) -> None:
        clock[0] += s

    code = watch(
        children,
        {"K": "v"},
        lambda: clock[0] >= until,
        policy,
        said.append,
        lambda: clock[0],
        sleep,
    )
    return code, said


def test_a_dead_process_is_restarted_after_its_backoff_and_the_others_are_left_alone() -> None:
    clock = [0.0]
    sub = Fake("subbroker", [5.0], clock)  # dies 5 s in, then runs for good
    pub = Fake("pubbroker", [1e9], clock)
    code, said = run([pub, sub], clock, until=30.0)
    assert code == 0  # stopped by Ctrl-C (stopping()), not by a death
    assert pub.starts == []  # never restarted
    assert len(sub.starts) == 1 and 6.0 <= sub.starts[0] <= 6.5  # 5 s + the 1 s backoff
    assert any("subbroker exited (9)" in s and "restarting it in 1 s" in s for s in said)
    assert any("restarted subbroker (pid 1001), restart 1 of at most 5" in s for s in said)


def test_a_process_that_keeps_dying_stops_the_run() -> None:
    clock = [0.0]
    sub = Fake("subbroker", [0.5] * 10, clock)
    code, said = run([sub], clock, until=1e6, policy=RestartPolicy(max_restarts=3))
    assert code == 1
    assert len(sub.starts) == 3
    gaps = [b - a for a, b in zip([0.0, *sub.starts], sub.starts, strict=False)]
    assert [round(g) for g in gaps] == [2, 3, 5]  # 0.5 s of life + 1, 2, 4 s of backoff
    assert "stopping the run: 3 restarts within 300 s" in said[-1]


def test_a_process_that_cannot_be_restarted_stops_the_run_at_once() -> None:
    clock = [0.0]
    radio = Fake("radio", [2.0], clock, restartable=False)
    code, said = run([radio], clock, until=1e6)
    assert code == 1 and radio.starts == []
    assert "radio exited (9)" in said[-1] and "it cannot be restarted" in said[-1]
