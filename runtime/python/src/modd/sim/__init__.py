"""``modd-sim --model FILE``: the simulated drone of a model.

- A simulated **autopilot** (``autopilot.py``) speaks MAVLink 2 over UDP on
  loopback (``--mavlink udpout:127.0.0.1:14550`` by default): HEARTBEAT at 1 Hz,
  GLOBAL_POSITION_INT, ATTITUDE, SYS_STATUS, VFR_HUD, GPS_RAW_INT and
  SYSTEM_TIME, each at 1 Hz until the MAVLink bridge (``modd-mavlink``) asks
  for other rates with SET_MESSAGE_INTERVAL. The topics of the model's ``kind
  mavlink`` sensors reach the PubBroker through the bridge, not from here.
- Simulated **scientific sensors** (``sensors.py``): every other topic is
  published through the Python publisher client, at its publisher's period,
  to the PubBroker's ingress (the model's, or ``--ingress``).
- Simulated **instruments** (``instruments.py``): the model's ``kind nmea``,
  ``ascii`` and ``modbus`` sensors each get a pseudo-terminal linked at their
  device path, where their wire format is written (``wire.py``: NMEA
  sentences, CSV or ``key=value`` lines, answers to Modbus reads) for
  ``modd-sensors`` to read (``--no-instruments``: their topics are published
  directly instead).
- ``--no-mavlink``: no autopilot; every topic of the model, the mavlink
  sensors' included, is published directly at its publisher's period. Models
  with no mavlink sensor run no autopilot either.

Both follow one survey track (``track.py``: back-and-forth legs over a stretch
of water, starting at ``--start-time``, default now), so the values mean
something: position and attitude follow the track, the accelerometer sees the
waves, and water temperature and conductivity vary in space (a warm, fresh
plume near one corner), so a track coloured by them shows a pattern.

Example::

    modd-sim --model demo.modd --mavlink udpout:127.0.0.1:14550 --duration 60
"""

from .cli import main
from .track import LEG_M, METERS_PER_DEG_LAT, ORIGIN_LAT, ORIGIN_LON, Pose, survey_pose

__all__ = ["LEG_M", "METERS_PER_DEG_LAT", "ORIGIN_LAT", "ORIGIN_LON", "Pose", "main", "survey_pose"]
