"""The CF standard-name table, shipped with MoDD (``data/cf_standard_names.tsv``,
derived from the CF table's XML; never fetched at run time): does a name exist,
and which unit must a variable of that name convert to.

>>> canonical_units("sea_water_temperature")
'K'
>>> canonical_units("no_such_name") is None
True

Refresh the table from a newer XML (cfconventions.org, or the copy the
``compliance-checker`` package ships)::

    python -m modd_model.standard_names cf-standard-name-table.xml
"""

from __future__ import annotations

import argparse
import xml.etree.ElementTree as ET
from functools import cache
from importlib import resources
from pathlib import Path

TABLE = "cf_standard_names.tsv"


@cache
def _table() -> tuple[str, dict[str, str], dict[str, str]]:
    """(version line, name -> canonical units, alias -> name)."""
    text = resources.files(__package__).joinpath("data", TABLE).read_text(encoding="utf-8")
    version, names, aliases = "", {}, {}
    for line in text.splitlines():
        if line.startswith("#"):
            version = version or line.lstrip("# ")
            continue
        name, _, units = line.partition("\t")
        if units.startswith("="):
            aliases[name] = units[1:]
        else:
            names[name] = units
    return version, names, aliases


def table_version() -> str:
    """Which CF table the shipped file was derived from."""
    return _table()[0]


def canonical_units(name: str) -> str | None:
    """The canonical unit of a standard name (or of the name an alias stands
    for); None for a name the table does not hold."""
    _, names, aliases = _table()
    return names.get(aliases.get(name, name))


def current_name(name: str) -> str | None:
    """The name an alias was renamed to, or None when ``name`` is not an alias."""
    return _table()[2].get(name)


def convert(xml_path: Path) -> str:
    """The shipped table's text, from the CF table's XML."""
    root = ET.parse(xml_path).getroot()  # noqa: S314 - a file the maintainer chose
    version = root.findtext("version_number", "?")
    lines = [
        f"# CF standard name table version {version}, "
        f"{root.findtext('last_modified', '?')} (from {xml_path.name}): "
        "name<TAB>canonical units, or alias<TAB>=name"
    ]
    for entry in root.iter("entry"):
        lines.append(f"{entry.get('id')}\t{(entry.findtext('canonical_units') or '').strip()}")
    for alias in root.iter("alias"):
        lines.append(f"{alias.get('id')}\t={(alias.findtext('entry_id') or '').strip()}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="rewrite data/cf_standard_names.tsv from XML")
    parser.add_argument("xml", type=Path)
    args = parser.parse_args(argv)
    out = Path(__file__).with_name("data") / TABLE
    out.write_text(convert(args.xml), encoding="utf-8")
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
