"""The dataset's discovery metadata (ACDD 1.3, IOOS Metadata Profile 1.2):
who made the data, who publishes it, under which license, from which
platform and instruments. Declared by the scientist in a YAML or JSON file
(``modd dataset --metadata FILE``, or ``dataset.yaml`` / ``dataset.json``
beside the model: the project's file, versioned with the model) whose keys
are the ACDD/IOOS attribute names (docs/user-guide/datasets.md, "Metadata").

Nothing is invented: an attribute the file does not give is left out (the
export's notes name the ones ACDD and IOOS ask for), except those MoDD knows
(title, summary, keywords, the platform's name and id, the instruments'
names).

>>> m = parse_metadata({"creator_name": "Ana", "keywords": ["ocean", "ctd"]}, "m.yaml")
>>> m.attributes["keywords"]
'ocean, ctd'
>>> parse_metadata({"naming_authority": "modd"}, "m")
Traceback (most recent call last):
...
modd.dataset.metadata.MetadataError: m: naming_authority 'modd' is not reversed DNS (org.example)
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .qcconfig import QcConfigError, parse_qc

#: Asked for by ACDD 1.3 / IOOS 1.2 and not known to MoDD: named in the notes when absent.
ASKED = (
    "creator_name",
    "creator_email",
    "creator_url",
    "creator_institution",
    "creator_country",
    "creator_sector",
    "publisher_name",
    "publisher_email",
    "publisher_url",
    "publisher_institution",
    "publisher_country",
    "institution",
    "license",
    "naming_authority",
    "infoUrl",
    "contributor_name",
    "contributor_role",
)
#: The global attributes a metadata file may give (ACDD 1.3 and IOOS 1.2 names).
GLOBAL_KEYS = (
    "title",
    "summary",
    "keywords",
    "keywords_vocabulary",
    "id",
    "project",
    "program",
    "acknowledgement",
    "references",
    "comment",
    "creator_type",
    "publisher_type",
    "contributor_email",
    "contributor_url",
    "contributor_role_vocabulary",
    "platform_vocabulary",
    "platform_id",
    "platform_name",
    "instrument_vocabulary",
    "sea_name",
) + ASKED
#: The platform variable's attributes (IOOS 1.2: ``platform`` names it).
PLATFORM_KEYS = ("name", "id", "type", "ioos_code", "wmo_code", "vocabulary", "comment")
#: An instrument's attributes (per sensor of the model).
INSTRUMENT_KEYS = ("make", "model", "serial_number", "vocabulary", "comment", "calibration_date")
_DNS = re.compile(r"^[a-z0-9-]+(\.[a-z0-9-]+)+$", re.IGNORECASE)
_EMAIL = re.compile(r"^[^@\s,]+@[^@\s,]+\.[^@\s,.]+$")
_URL = re.compile(r"^https?://[^\s/]+\.[^\s]*$|^https?://[^\s/]+$", re.IGNORECASE)


class MetadataError(ValueError):
    """A metadata file that cannot be used, located (file, key): ``key`` is the
    dotted key at fault (``creator_email``, ``platform.id``), None for the whole file."""

    def __init__(self, message: str, key: str | None = None) -> None:
        super().__init__(message)
        self.key = key


@dataclass
class Metadata:
    """Global attributes, the platform's and each instrument's (by sensor name)."""

    attributes: dict[str, str] = field(default_factory=dict)
    platform: dict[str, str] = field(default_factory=dict)
    instruments: dict[str, dict[str, str]] = field(default_factory=dict)
    source: str | None = None  # the file it came from (its name only)
    #: QARTOD tests by topic (qc.py): ``{topic: {ioos_qc test: {parameter: value}}}``.
    qc: dict[str, dict[str, dict[str, Any]]] = field(default_factory=dict)
    #: Topics whose variables are marked for NDBC's ingest to the GTS (IOOS 1.2
    #: ``gts_ingest = "true"`` on them and on the file).
    gts_ingest: tuple[str, ...] = ()

    def missing(self) -> list[str]:
        """The ACDD/IOOS attributes asked for that the file did not give."""
        return [k for k in ASKED if k not in self.attributes]


def _text(value: Any, where: str, key: str | None = None) -> str:
    if isinstance(value, list) and all(isinstance(v, str | int | float) for v in value):
        return ", ".join(str(v) for v in value)
    if isinstance(value, str | int | float) and not isinstance(value, bool):
        return str(value)
    raise MetadataError(f"{where}: a text or a list of texts, not {type(value).__name__}", key)


def _check_forms(attrs: dict[str, str], source: str) -> None:
    """Reversed DNS, e-mail addresses and URLs in their form (the first fault, located).

    >>> _check_forms({"creator_email": "ana at example.org"}, "m")
    Traceback (most recent call last):
    ...
    modd.dataset.metadata.MetadataError: m: creator_email 'ana at example.org' is not an \
e-mail address (name@example.org)
    """
    for key, value in attrs.items():
        if key == "naming_authority" and not _DNS.match(value):
            raise MetadataError(
                f"{source}: naming_authority {value!r} is not reversed DNS (org.example)", key
            )
        if key.endswith("_email") and not all(_EMAIL.match(v.strip()) for v in value.split(",")):
            raise MetadataError(
                f"{source}: {key} {value!r} is not an e-mail address (name@example.org)", key
            )
        if (key.endswith("_url") or key == "infoUrl") and not _URL.match(value):
            raise MetadataError(f"{source}: {key} {value!r} is not an http(s) URL", key)


def _table(doc: Any, keys: tuple[str, ...], source: str, path: str = "") -> dict[str, str]:
    """The texts of a mapping; errors say ``SOURCE: PATH: ...`` (``PATH.KEY`` for a value)."""
    where = f"{source}: {path}" if path else source
    if not isinstance(doc, dict):
        raise MetadataError(f"{where}: a mapping of {', '.join(keys)}", path or None)
    dot = f"{path}." if path else ""
    unknown = sorted(str(k) for k in doc if k not in keys)
    if unknown:
        raise MetadataError(
            f"{where}: unknown key {unknown[0]!r}; one of {', '.join(keys)}", f"{dot}{unknown[0]}"
        )
    return {
        k: _text(v, f"{source}: {dot}{k}", f"{dot}{k}") for k, v in doc.items() if v is not None
    }


def parse_metadata(doc: Any, source: str) -> Metadata:
    """The metadata of a parsed file; raises MetadataError naming ``source`` and the key."""
    if not isinstance(doc, dict):
        raise MetadataError(f"{source}: a mapping of attribute names to values")
    rest = {
        k: v for k, v in doc.items() if k not in ("platform", "instruments", "qc", "gts_ingest")
    }
    attrs = _table(rest, GLOBAL_KEYS, source)
    _check_forms(attrs, source)
    platform = _table(doc.get("platform") or {}, PLATFORM_KEYS, source, "platform")
    sensors = doc.get("instruments") or {}
    if not isinstance(sensors, dict):
        raise MetadataError(
            f"{source}: instruments: a mapping of sensor names to instruments", "instruments"
        )
    instruments = {
        str(name): _table(inst, INSTRUMENT_KEYS, source, f"instruments.{name}")
        for name, inst in sensors.items()
    }
    try:
        qc = parse_qc(doc["qc"], source) if doc.get("qc") is not None else {}
    except QcConfigError as exc:
        raise MetadataError(str(exc), "qc") from None
    gts = doc.get("gts_ingest") or []
    if not isinstance(gts, list) or not all(isinstance(t, str) and t for t in gts):
        raise MetadataError(f"{source}: gts_ingest: a list of topics", "gts_ingest")
    return Metadata(attrs, platform, instruments, Path(source).name, qc, tuple(gts))


def load_metadata(path: Path) -> Metadata:
    """A YAML (``.yaml``/``.yml``) or JSON file's metadata; raises MetadataError."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise MetadataError(f"{path}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise MetadataError(f"{path}: not UTF-8 text") from None
    if path.suffix.lower() in (".yaml", ".yml"):
        import yaml

        try:
            doc = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            mark = getattr(exc, "problem_mark", None)
            at = f"line {mark.line + 1}: " if mark is not None else ""
            raise MetadataError(f"{path}: {at}not YAML ({getattr(exc, 'problem', exc)})") from None
    else:
        try:
            doc = json.loads(text)
        except json.JSONDecodeError as exc:
            raise MetadataError(f"{path}: line {exc.lineno}: not JSON ({exc.msg})") from None
    return parse_metadata(doc, str(path))


def project_metadata(model_path: Path) -> Path | None:
    """The project's metadata file beside the model (``dataset.yaml``,
    ``dataset.yml`` or ``dataset.json``), if there is one."""
    for name in ("dataset.yaml", "dataset.yml", "dataset.json"):
        candidate = model_path.parent / name
        if candidate.is_file():
            return candidate
    return None
