"""The instrument's clock (``clock = instrument``): a sentence that states its
UTC time of day (GGA, GNS, RMC, GLL, ZDA, GST …) is stamped with that time, on
the date of the last valid RMC (status A) or ZDA (a void RMC's date may be the
receiver's default, 1980-01-05, before it has one); a sentence without one
(VTG, GSA, HDT …) takes the time of its fix epoch (the last time stated). The
date follows the times
across midnight (23:59:59 then 00:00:00 is the next day) until the next RMC/ZDA
says it.

Until the instrument has stated a date, samples are *held* (at most
``HOLD_MAX``; older ones dropped and counted missing) and stamped when it does:
a topic never mixes the instrument's clock with the computer's.

Dates are resolved against the computer's clock (``now_ns``): a two-digit
year is the one of its century nearest the computer's year; then a date more
than 512 GPS weeks from the computer's is moved by whole 1024-week GPS
rollovers to the nearest (a receiver confused by a week rollover states a date
1024 weeks early). The computer's clock needs only be right within ~9.8 years.

Example::

    clock = InstrumentClock()
    clock.observe(rmc_sentence, now_ns)     # its date and time
    clock.stamp(gga_sentence)               # GGA's own time on that date (None: hold)
"""

from __future__ import annotations

import calendar
import datetime

from .nmea import Sentence, stated_date, time_of_day

DAY_NS = 86_400 * 10**9
ROLLOVER_DAYS = 1024 * 7  # one GPS week-number rollover (10-bit week)
HOLD_MAX = 512  # samples held until the instrument's date is known


def resolve_date(year: int, month: int, day: int, two_digit: bool, now_ns: int) -> int:
    """Midnight (ns since the Unix epoch) of the date, resolved against ``now_ns``."""
    now_day = now_ns // DAY_NS
    if two_digit:
        this = datetime.datetime.fromtimestamp(now_ns / 1e9, datetime.UTC).year
        year = min(
            (c + year for c in range(this // 100 * 100 - 100, this + 101, 100)),
            key=lambda y: abs(y - this),
        )
    try:
        days = calendar.timegm((year, month, day, 0, 0, 0)) // 86_400
        datetime.date(year, month, day)  # refuses 31 February
    except (ValueError, OverflowError) as exc:
        raise ValueError(f"date {year:04d}-{month:02d}-{day:02d}") from exc
    shift = round((now_day - days) / ROLLOVER_DAYS)
    return (days + shift * ROLLOVER_DAYS) * DAY_NS


class InstrumentClock:
    """The instrument's time of the sentences it reads, one sentence after another."""

    def __init__(self) -> None:
        self.midnight_ns: int | None = None  # of the instrument's current date
        self.epoch_ns: int | None = None  # the last stamp stated: the fix epoch's time
        self.epoch_tod_ns: int | None = None  # its time of day, while no date is known

    def observe(self, s: Sentence, now_ns: int) -> int | None:
        """Takes the sentence's date and time; its stamp (None: no date known yet)."""
        tod = time_of_day(s)
        date = stated_date(s) if s.type == "ZDA" or s.fields[1:2] == ("A",) else None
        if date is not None and tod is not None:
            try:
                self.midnight_ns = resolve_date(*date, now_ns)
            except ValueError:
                pass
            else:
                self.epoch_ns = self.midnight_ns + round(tod * 1e9)
                return self.epoch_ns
        if tod is None:
            return self.epoch_ns
        tod_ns = round(tod * 1e9)
        self.epoch_tod_ns = tod_ns
        if self.midnight_ns is None:
            return None
        self.epoch_ns = self.on_date(tod_ns)
        return self.epoch_ns

    def on_date(self, tod_ns: int) -> int:
        """A time of day on the instrument's date: of the day before, that day or the
        next, the nearest to the last epoch (the next one moves the date on: midnight)."""
        assert self.midnight_ns is not None
        ref = self.epoch_ns if self.epoch_ns is not None else self.midnight_ns + tod_ns
        k = min((-1, 0, 1), key=lambda k: abs(self.midnight_ns + k * DAY_NS + tod_ns - ref))  # type: ignore[operator]
        if k == 1:
            self.midnight_ns += DAY_NS
            k = 0
        return self.midnight_ns + k * DAY_NS + tod_ns

    def pending_tod(self, s: Sentence) -> int | None:
        """The time of day a held sample is stamped with later (its own, or its epoch's)."""
        tod = time_of_day(s)
        return round(tod * 1e9) if tod is not None else self.epoch_tod_ns
