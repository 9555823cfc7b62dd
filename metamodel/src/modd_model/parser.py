"""The .modd text → a model document (the JSON the schema describes) and a
source map from JSON pointers to text positions.

Three steps, kept apart: the grammar (``modd.lark``) says what is well-formed;
``_Builder`` turns the parse tree into the document, checking the words the
grammar leaves open (units, value types, aggregations, setting names); the
validator (``validate.py``) checks meaning. Every error carries file:line:col."""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from lark import Lark, Token, Tree
    from lark.exceptions import (
        UnexpectedCharacters,
        UnexpectedEOF,
        UnexpectedInput,
        UnexpectedToken,
    )
else:  # the standalone parser generated from modd.lark: lark is not imported at run time
    from ._modd_parser_gen import (
        Lark,
        Token,
        Tree,
        UnexpectedCharacters,
        UnexpectedEOF,
        UnexpectedInput,
        UnexpectedToken,
    )

from modd_contracts import aggregations_gen as agg

from .diagnostics import Diagnostic, Location, ModelError, pointer_join
from .numbers import canonical_decimal
from .vocabulary import (
    AGGREGATIONS,
    ALERT_ROLES,
    BACKFILL_POLICIES,
    SCHEMA_VERSION,
    SENSOR_KINDS,
    VALUE_TYPES,
)

SourceMap = dict[str, Location]

# Settings blocks: DSL word -> (JSON property, kind).
LINK_SETTINGS = {
    "transport": ("transport", "word"),
    "device": ("device", "string"),
    "droneDevice": ("droneDevice", "string"),
    "baud": ("baud", "int"),
    "rate": ("rateBps", "int"),
    "packet": ("maxPacket", "int"),
    "delay": ("acceptedDelayS", "decimal"),
    "key": ("keyRef", "string"),
    "rtt": ("expectedRttS", "decimal"),
    "maxBuffer": ("maxBuffer", "int"),
    "ping": ("pingS", "decimal"),
    "alpha": ("alpha", "decimal"),
    "beta": ("beta", "decimal"),
}
# The link's radio profile, written flat inside `Link { ... }` (radio = lora;
# sf = 7; ...) and held in JSON as link.radio: the "radio/" prefix nests it.
RADIO_SETTINGS = {
    "radio": ("radio/kind", "word"),
    "airRate": ("radio/airRateBps", "int"),
    "ecc": ("radio/ecc", "bool"),
    "sf": ("radio/spreadingFactor", "int"),
    "bandwidth": ("radio/bandwidthHz", "int"),
    "codingRate": ("radio/codingRate", "int"),
    "preamble": ("radio/preamble", "int"),
    "explicitHeader": ("radio/explicitHeader", "bool"),
    "crc": ("radio/crc", "bool"),
    "lowDataRate": ("radio/lowDataRate", "bool"),
    "maxPayload": ("radio/maxPayload", "int"),
    "dutyCycle": ("radio/dutyCycle", "decimal"),
    "txW": ("radio/txW", "decimal"),
    "rxW": ("radio/rxW", "decimal"),
    "idleW": ("radio/idleW", "decimal"),
    "battery": ("radio/batteryWh", "decimal"),
}
INGRESS_SETTINGS = {"socket": ("unixSocket", "string"), "port": ("tcpPort", "int")}
# An instrument sensor's settings (`on "PATH" { ... }`): a "/" in the property nests it.
SENSOR_SETTINGS = {
    "baud": ("device/baud", "int"),
    "parity": ("device/parity", "word"),
    "stop": ("device/stopBits", "int"),
    "separator": ("line/separator", "string"),
    "terminator": ("line/terminator", "word"),
    "start": ("line/startCommand", "string"),
    "pattern": ("line/pattern", "string"),
    "clock": ("clock", "word"),
    "checksum": ("checksum", "word"),
    "fix": ("fix", "word"),
}
CHANNEL_SETTINGS = {"rate": ("rateBps", "int"), "dutyCycle": ("dutyCycle", "decimal")}
POSITION_SETTINGS = {
    "latitude": ("latitude", "string"),
    "longitude": ("longitude", "string"),
    "altitude": ("altitude", "string"),
    "maxGap": ("maxGapS", "decimal"),
}
# A variable's attributes block: DSL word -> (JSON property, kind); kind "number"
# takes a signed number, "text" a string, "name" a bare word.
VARIABLE_ATTRIBUTES = {
    "standardName": ("standardName", "name"),
    "longName": ("longName", "text"),
    "validMin": ("validMin", "number"),
    "validMax": ("validMax", "number"),
    "resolution": ("resolution", "number"),
}

_TERMINAL_NAMES = {
    "NAME": "a name",
    "NUMBER": "a number",
    "STRING": "a string in double quotes",
    "SCALAR": "a number",
    "$END": "end of file",
}


@cache
def _parser() -> Lark:
    """The LALR parser of modd.lark (``parser="lalr", propagate_positions=True,
    maybe_placeholders=False``), generated ahead of time into _modd_parser_gen.py:
    building it from the grammar at each start cost ~0.27 s of CPU."""
    from ._modd_parser_gen import Lark_StandAlone

    parser: Lark = Lark_StandAlone()  # type: ignore[no-untyped-call]
    return parser


def parse_text(text: str, filename: str = "<text>") -> tuple[dict[str, Any], SourceMap]:
    """Parse .modd text into a model document and its source map.

    Raises ModelError with located diagnostics on a syntax error or an unknown word.

    >>> doc, _ = parse_text('Drone d { Sensors { Sensor s measures { v(METER); } } }'
    ...     ' PubBroker("127.0.0.1":1, "/l"); SubBroker("127.0.0.1":2, "/c");')
    >>> doc["drone"]["sensors"][0]["variables"][0]
    {'name': 'v', 'unit': 'METER'}
    """
    doc, smap, diagnostics = parse_lenient(text, filename)
    if doc is None or diagnostics:
        raise ModelError(diagnostics)
    return doc, smap


def parse_lenient(
    text: str, filename: str = "<text>"
) -> tuple[dict[str, Any] | None, SourceMap, list[Diagnostic]]:
    """Like parse_text, but returns the document even when some words in it are
    wrong (unknown unit, aggregation, ...), with those errors, so that the
    validator can report the model's other problems in the same run. The
    document is None only on a syntax error."""
    lines = text.splitlines()
    try:
        tree = _parser().parse(text)
    except UnexpectedInput as exc:
        diagnostic = _syntax_diagnostic(exc, filename, lines)
        return None, {}, [_runaway_string(text, diagnostic, lines) or diagnostic]
    builder = _Builder(filename, lines)
    doc = builder.build(tree)
    return doc, builder.source_map, builder.diagnostics


def _describe_expected(expected: set[str]) -> str:
    names: list[str] = []
    terminals = {t.name: t for t in _parser().terminals}
    for name in sorted(expected):
        if name in _TERMINAL_NAMES:
            names.append(_TERMINAL_NAMES[name])
        elif name in terminals and terminals[name].pattern.type == "str":
            names.append(f"'{terminals[name].pattern.value}'")
        else:
            names.append(name)
    names = sorted(set(names))
    if len(names) == 1:
        return names[0]
    return ", ".join(names[:-1]) + " or " + names[-1]


def _runaway_string(text: str, error: Diagnostic, lines: list[str]) -> Diagnostic | None:
    """Strings may span lines (as in Xtext), so a missing closing quote shows up
    lines later; point at the string that ran over a line end instead."""
    assert error.location is not None
    err_line, suspect = error.location.line, None
    try:
        for tok in _parser().lex(text):
            if (tok.line or 0) >= err_line:
                break
            if tok.type == "STRING" and "\n" in str(tok):
                suspect = tok
    except UnexpectedInput:
        pass
    if suspect is None or suspect.end_line != err_line:
        return None
    line, col = suspect.line or 1, suspect.column or 1
    src = lines[line - 1] if 0 < line <= len(lines) else None
    return Diagnostic(
        f"the string that starts here runs over the end of its line and on to "
        f"line {suspect.end_line}, where the syntax error is ({error.message}); "
        f"is a closing quote missing?",
        "",
        "error",
        Location(error.location.file, line, col),
        src,
    )


def _syntax_diagnostic(exc: UnexpectedInput, filename: str, lines: list[str]) -> Diagnostic:
    line = getattr(exc, "line", 1) or 1
    col = getattr(exc, "column", 1) or 1
    if isinstance(exc, UnexpectedToken) and exc.token.type == "$END":
        line, col = max(len(lines), 1), len(lines[-1]) + 1 if lines else 1
        message = f"unexpected end of file, expected {_describe_expected(exc.expected)}"
    elif (
        isinstance(exc, UnexpectedToken) and exc.token.type == "SCALAR" and "NUMBER" in exc.expected
    ):
        message = f"expected an unsigned decimal number, found {exc.token.value!r}"
    elif isinstance(exc, UnexpectedToken):
        message = f"unexpected {exc.token.value!r}, expected {_describe_expected(exc.expected)}"
    elif isinstance(exc, UnexpectedCharacters):
        message = f"unexpected character {exc.char!r}"
        if exc.allowed:
            message += f", expected {_describe_expected(set(exc.allowed))}"
    elif isinstance(exc, UnexpectedEOF):
        message = f"unexpected end of file, expected {_describe_expected(set(exc.expected))}"
    else:  # pragma: no cover - lark raises one of the above
        message = str(exc)
    src = lines[line - 1] if 0 < line <= len(lines) else None
    return Diagnostic(message, "", "error", Location(filename, line, col), src)


_ESCAPES = {"n": "\n", "t": "\t", "r": "\r", "b": "\b", "f": "\f"}
_HEX = frozenset("0123456789abcdefABCDEF")


def _unquote(token: Token) -> str:
    """The value of a string literal in either quote style, with the escapes of
    Xtext's STRING (\\n \\t \\r \\b \\f, \\u and four hex digits, and any other escaped character
    standing for itself)."""
    body = str(token)[1:-1]
    out: list[str] = []
    i = 0
    while i < len(body):
        c = body[i]
        if c == "\\" and i + 1 < len(body):
            nxt = body[i + 1]
            if nxt == "u" and len(body) >= i + 6 and set(body[i + 2 : i + 6]) <= _HEX:
                out.append(chr(int(body[i + 2 : i + 6], 16)))
                i += 6
                continue
            out.append(_ESCAPES.get(nxt, nxt))
            i += 2
        else:
            out.append(c)
            i += 1
    return "".join(out)


def _word(token: Token) -> str:
    """A name written as an identifier (``^`` escape removed) or as a string."""
    if token.type == "STRING":
        return _unquote(token)
    return str(token).removeprefix("^")


def _topic(node: Token | Tree[Token]) -> str:
    """A topic written as a string or as a bare qualified name."""
    if isinstance(node, Token):
        return _unquote(node)
    return ".".join(_word(t) for t in node.children if isinstance(t, Token))


#: The parameters each aggregation takes in parentheses, in order (docs/dsl.md).
_AGG_FIELDS: dict[str, tuple[str, ...]] = {
    agg.PERCENTILE: ("percentile",),
    agg.ON_CHANGE: ("deadband",),
    agg.THRESHOLD: ("crossing", "level", "hysteresis"),
}
_AGG_SYNTAX = "PERCENTILE(95), ON_CHANGE(0.5), ON_CHANGE(5%), THRESHOLD(DOWN 5.0, 0.2)"


class _Builder:
    """Walks the parse tree and assembles the model document, recording where
    each JSON pointer came from."""

    def __init__(self, filename: str, lines: list[str]) -> None:
        self.filename = filename
        self.lines = lines
        self.diagnostics: list[Diagnostic] = []
        self.source_map: SourceMap = {}

    # -- helpers -------------------------------------------------------
    def _loc(self, node: Tree[Token] | Token) -> Location:
        if isinstance(node, Token):
            return Location(
                self.filename, node.line or 1, node.column or 1, node.end_line, node.end_column
            )
        meta = node.meta
        if getattr(meta, "empty", True):
            return Location(self.filename, 1, 1)
        return Location(self.filename, meta.line, meta.column, meta.end_line, meta.end_column)

    def _mark(self, pointer: str, node: Tree[Token] | Token) -> None:
        self.source_map.setdefault(pointer, self._loc(node))

    def _error(self, node: Tree[Token] | Token, message: str, pointer: str = "") -> None:
        loc = self._loc(node)
        src = self.lines[loc.line - 1] if 0 < loc.line <= len(self.lines) else None
        self.diagnostics.append(Diagnostic(message, pointer, "error", loc, src))

    def _decimal(self, token: Token, pointer: str = "") -> str:
        try:
            return canonical_decimal(str(token))
        except ValueError as exc:
            self._error(token, str(exc), pointer)
            return "0.0"

    def _agg_args(self, node: Tree[Token], aggregation: str, ptr: str) -> dict[str, Any]:
        """An aggregation's parameters as written, by its aggregation: PERCENTILE(p),
        ON_CHANGE(d) or ON_CHANGE(p%), THRESHOLD([UP|DOWN|BOTH] level[, hysteresis]);
        their ranges are the schema's and the validator's to check, located."""
        tokens = [t for t in node.children if isinstance(t, Token)]
        word = [t for t in tokens if t.type == "NAME"]
        numbers = [t for t in tokens if t.type == "SCALAR"]
        percent = any(t.type == "PERCENT" for t in tokens)
        fields = _AGG_FIELDS.get(aggregation)
        if fields is None and not word and not percent and len(numbers) == 1:
            fields = _AGG_FIELDS[agg.PERCENTILE]  # MEDIAN(5): the validator says it takes no p
        numeric = [f for f in fields or () if f != "crossing"]
        shape_ok = fields is not None and len(numbers) <= len(numeric)
        if aggregation != agg.THRESHOLD and word or percent and aggregation != agg.ON_CHANGE:
            shape_ok = False
        if not shape_ok or fields is None:
            self._error(
                tokens[0],
                f"{aggregation} takes no such parameters ({_AGG_SYNTAX})",
                ptr + "/aggregation",
            )
            return {}
        out: dict[str, Any] = {}
        if word:
            crossing = str(word[0])
            self._mark(ptr + "/crossing", word[0])
            if crossing not in ("UP", "DOWN", "BOTH"):
                self._error(
                    word[0],
                    f"unknown crossing {crossing!r}; expected UP, DOWN or BOTH",
                    ptr + "/crossing",
                )
            out["crossing"] = crossing.lower()
        names = ["deadbandPercent"] if percent else numeric
        for key, token in zip(names, numbers, strict=False):
            self._mark(f"{ptr}/{key}", token)
            out[key] = float(token)
        return out

    def _int(self, token: Token, pointer: str) -> int:
        text = str(token)
        if not text.isdigit():
            self._error(token, f"expected a whole number, found {text!r}", pointer)
            return 0
        return int(text)

    # -- the document ----------------------------------------------------
    def build(self, tree: Tree[Token]) -> dict[str, Any]:
        doc: dict[str, Any] = {"schemaVersion": SCHEMA_VERSION}
        publishers: list[dict[str, Any]] = []
        subscribers: list[dict[str, Any]] = []
        seen: dict[str, Tree[Token]] = {}
        for block in tree.children:
            assert isinstance(block, Tree)
            kind = str(block.data)
            if kind in ("drone", "pubbroker", "subbroker", "link", "campaign"):
                if kind in seen:
                    first = self._loc(seen[kind])
                    self._error(
                        block,
                        f"a second {_BLOCK_WORD[kind]} block; the first is at line {first.line}",
                    )
                    continue
                seen[kind] = block
            if kind == "drone":
                doc["drone"] = self._drone(block)
            elif kind == "pubbroker":
                doc["pubBroker"] = self._broker(block, "/pubBroker", "logPath")
            elif kind == "subbroker":
                doc["subBroker"] = self._broker(block, "/subBroker", "configPath")
            elif kind == "link":
                doc["link"] = _nest(
                    self._settings(block.children[0], "/link", LINK_SETTINGS | RADIO_SETTINGS)
                )
                self._mark("/link", block)
            elif kind == "campaign":
                doc["campaign"] = self._campaign(block)
            elif kind == "publishers":
                self._mark("/publishers", block)
                for p in block.children:
                    assert isinstance(p, Tree)
                    publishers.append(self._publisher(p, len(publishers)))
            elif kind == "subscriptions":
                self._mark("/subscribers", block)
                for s in block.children:
                    assert isinstance(s, Tree)
                    subscribers.append(self._subscriber(s, len(subscribers)))
        for kind in ("drone", "pubbroker", "subbroker"):
            if kind not in seen:
                self._error(tree, f"the model has no {_BLOCK_WORD[kind]} block")
        doc["publishers"] = publishers
        doc["subscribers"] = subscribers
        _qualify_topics(doc)
        return _ordered(doc)

    def _drone(self, node: Tree[Token]) -> dict[str, Any]:
        name, rest = node.children[0], node.children[1:]
        assert isinstance(name, Token)
        drone: dict[str, Any] = {"name": _word(name)}
        self._mark("/drone", node)
        self._mark("/drone/name", name)
        sensors: list[dict[str, Any]] = []
        for child in rest:
            assert isinstance(child, Tree)
            if child.data == "description":
                drone["description"] = _unquote(child.children[0])  # type: ignore[arg-type]
                continue
            if child.data == "position":
                if "position" in drone:
                    self._error(child, "a second Position block", "/drone/position")
                self._mark("/drone/position", child)
                drone["position"] = self._settings(
                    child.children[0], "/drone/position", POSITION_SETTINGS
                )
                continue
            self._mark("/drone/sensors", child)
            for s in child.children:
                assert isinstance(s, Tree)
                sensors.append(self._sensor(s, f"/drone/sensors/{len(sensors)}"))
        drone["sensors"] = sensors
        order = ["name", "description", "sensors", "position"]
        return {k: drone[k] for k in order if k in drone}

    def _sensor(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        name = node.children[0]
        assert isinstance(name, Token)
        sensor: dict[str, Any] = {"name": _word(name)}
        self._mark(ptr, node)
        self._mark(ptr + "/name", name)
        variables: list[dict[str, Any]] = []
        for child in node.children[1:]:
            assert isinstance(child, Tree)
            if child.data == "description":
                sensor["description"] = _unquote(child.children[0])  # type: ignore[arg-type]
            elif child.data == "sensor_kind":
                kind = child.children[0]
                assert isinstance(kind, Token)
                self._mark(ptr + "/kind", kind)
                if str(kind) not in SENSOR_KINDS:
                    self._error(
                        kind,
                        f"unknown sensor kind {str(kind)!r}; expected one of "
                        f"{', '.join(SENSOR_KINDS)}",
                        ptr + "/kind",
                    )
                sensor["kind"] = str(kind)
            elif child.data == "device":
                path, *settings = child.children
                assert isinstance(path, Tree) and isinstance(path.children[0], Token)
                self._mark(ptr + "/device", child)
                self._mark(ptr + "/device/path", path.children[0])
                sensor["device"] = {"path": _word(path.children[0])}
                for block in settings:
                    self._sensor_settings(sensor, block, ptr)
            elif child.data == "sensor_settings":
                self._sensor_settings(sensor, child.children[0], ptr)
            else:
                variables.append(self._variable(child, f"{ptr}/variables/{len(variables)}"))
        sensor["variables"] = variables
        return sensor

    def _sensor_settings(self, sensor: dict[str, Any], node: Tree[Token] | Token, ptr: str) -> None:
        """``{ baud = 9600; ... }`` into the sensor's device, line and clock properties."""
        for prop, value in self._settings(node, ptr, SENSOR_SETTINGS).items():
            head, _, tail = prop.partition("/")
            if tail:
                sensor.setdefault(head, {})[tail] = value
            else:
                sensor[head] = value

    def _variable(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        name, unit_node, *rest = node.children
        assert isinstance(name, Token) and isinstance(unit_node, Tree)
        self._mark(ptr, node)
        self._mark(ptr + "/name", name)
        unit_tok = unit_node.children[0]
        assert isinstance(unit_tok, Token)
        self._mark(ptr + "/unit", unit_tok)
        # A bare word (the paper's METER_PER_SECOND_SQUARED, or degC) or a string
        # ("m s-2"): validation checks it is a UDUNITS unit (units.py).
        unit = _unquote(unit_tok) if unit_tok.type == "STRING" else str(unit_tok)
        var: dict[str, Any] = {"name": _word(name), "unit": unit}
        for child in rest:
            if isinstance(child, Token):
                self._mark(ptr + "/type", child)
                if str(child) not in VALUE_TYPES:
                    self._error(
                        child,
                        f"unknown value type {str(child)!r}; expected one of "
                        f"{', '.join(VALUE_TYPES)}",
                        ptr + "/type",
                    )
                var["type"] = str(child)
            elif child.data == "sentence_source":
                var["nmea"] = self._nmea_source(child, ptr + "/nmea")
            elif child.data == "source":
                var["source"] = self._source(child, ptr + "/source")
            elif child.data in ("column_source", "key_source"):
                var["ascii"] = self._ascii_source(child, ptr + "/ascii")
            elif child.data == "register_source":
                var["modbus"] = self._register_source(child, ptr + "/modbus")
            elif child.data == "meaning":
                var.update(self._attributes(child, ptr))
            else:
                var["description"] = _unquote(child.children[0])  # type: ignore[arg-type]
        return var

    def _attributes(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        """``{ standardName = ...; longName = "..."; validMin = -2; }`` of a variable."""
        out: dict[str, Any] = {}
        for attr in node.children:
            assert isinstance(attr, Tree)
            key_tok, value = attr.children
            assert isinstance(key_tok, Token) and isinstance(value, Token)
            key = str(key_tok)
            if key not in VARIABLE_ATTRIBUTES:
                self._error(
                    key_tok,
                    f"unknown attribute {key!r}; expected one of {', '.join(VARIABLE_ATTRIBUTES)}",
                    ptr,
                )
                continue
            prop, kind = VARIABLE_ATTRIBUTES[key]
            self._mark(f"{ptr}/{prop}", attr)
            if prop in out:
                self._error(key_tok, f"attribute {key!r} given twice", f"{ptr}/{prop}")
            found = {"SCALAR": "number", "STRING": "text", "NAME": "name"}[value.type]
            if found != kind:
                wanted = {"number": "a number", "text": "a string", "name": "a name"}[kind]
                self._error(value, f"attribute {key!r} takes {wanted}", f"{ptr}/{prop}")
                continue
            text = str(value)
            out[prop] = (
                float(text) if kind == "number" else (_unquote(value) if kind == "text" else text)
            )
        return {p: out[p] for p, _ in VARIABLE_ATTRIBUTES.values() if p in out}

    def _source(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        message, field, *factors = node.children
        self._mark(ptr, node)
        source: dict[str, Any] = {"message": str(message), "field": str(field)}
        for factor in factors:
            assert isinstance(factor, Tree)
            tok = factor.children[0]
            assert isinstance(tok, Token)
            source[str(factor.data)] = float(tok)
        return source

    def _factors(
        self, nodes: list[Tree[Token] | Token], out: dict[str, Any], ptr: str
    ) -> dict[str, Any]:
        """``scale X offset Y`` into ``out`` (located)."""
        for factor in nodes:
            assert isinstance(factor, Tree)
            tok = factor.children[0]
            assert isinstance(tok, Token)
            self._mark(f"{ptr}/{factor.data}", tok)
            out[str(factor.data)] = float(tok)
        return out

    def _nmea_source(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        sentence, field, *rest = node.children
        self._mark(ptr, node)
        self._mark(ptr + "/sentence", sentence)
        self._mark(ptr + "/field", field)
        factors, condition = _split_condition(rest)
        src = self._factors(factors, {"sentence": str(sentence), "field": str(field)}, ptr)
        if condition is not None:
            place, comparison, value = condition.children
            assert isinstance(place, Token)
            self._mark(ptr + "/where/field", place)
            src["where"] = {"field": str(place), **self._comparison(comparison, value, ptr)}
            self._mark(ptr + "/where", condition)
        return src

    def _ascii_source(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        where, *rest = node.children
        assert isinstance(where, Token)
        self._mark(ptr, node)
        factors, condition = _split_condition(rest)
        if node.data == "column_source":
            self._mark(ptr + "/column", where)
            src = self._factors(factors, {"column": self._int(where, ptr + "/column")}, ptr)
        else:
            self._mark(ptr + "/key", where)
            src = self._factors(factors, {"key": _word(where)}, ptr)
        if condition is not None:
            place, comparison, value = condition.children
            assert isinstance(place, Tree) and isinstance(place.children[0], Token)
            tok = place.children[0]
            self._mark(ptr + "/where", condition)
            if place.data == "where_column":
                self._mark(ptr + "/where/column", tok)
                cond: dict[str, Any] = {"column": self._int(tok, ptr + "/where/column")}
            else:
                self._mark(ptr + "/where/key", tok)
                cond = {"key": _word(tok)}
            src["where"] = {**cond, **self._comparison(comparison, value, ptr)}
        return src

    def _comparison(
        self, comparison: Tree[Token] | Token, value: Tree[Token] | Token, ptr: str
    ) -> dict[str, str]:
        """``op value`` of a source's ``where`` (the value as written; a string unquoted)."""
        assert isinstance(comparison, Tree) and isinstance(value, Tree)
        op, tok = comparison.children[0], value.children[0]
        assert isinstance(op, Token) and isinstance(tok, Token)
        self._mark(ptr + "/where/op", op)
        self._mark(ptr + "/where/value", tok)
        return {"op": str(op), "value": _word(tok)}

    def _register_source(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        register, rtype, *rest = node.children
        assert isinstance(register, Token) and isinstance(rtype, Token)
        self._mark(ptr, node)
        self._mark(ptr + "/register", register)
        self._mark(ptr + "/type", rtype)
        src: dict[str, Any] = {}
        factors: list[Tree[Token] | Token] = []
        for option in rest:
            assert isinstance(option, Tree)
            tok = option.children[0]
            assert isinstance(tok, Token)
            if option.data in ("scale", "offset"):
                factors.append(option)
            elif option.data == "unit_id":
                self._mark(ptr + "/unit", tok)
                src["unit"] = self._int(tok, ptr + "/unit")
            else:
                key = "table" if option.data == "table" else "wordOrder"
                self._mark(f"{ptr}/{key}", tok)
                src[key] = str(tok)
        src["register"] = self._int(register, ptr + "/register")
        src["type"] = str(rtype)
        order = ("unit", "register", "table", "type", "wordOrder")
        return self._factors(factors, {k: src[k] for k in order if k in src}, ptr)

    # -- a campaign (modd_model.campaign) -------------------------------------
    def _campaign(self, node: Tree[Token]) -> dict[str, Any]:
        name, rest = node.children[0], node.children[1:]
        assert isinstance(name, Token)
        self._mark("/campaign", node)
        self._mark("/campaign/name", name)
        out: dict[str, Any] = {"name": _word(name)}
        channels: list[dict[str, Any]] = []
        found: list[dict[str, Any]] = []
        for child in rest:
            assert isinstance(child, Tree)
            if child.data == "description":
                out["description"] = _unquote(child.children[0])  # type: ignore[arg-type]
            elif child.data == "channel":
                ptr = f"/campaign/channels/{len(channels)}"
                channels.append(self._channel(child, ptr))
            else:
                found.append(self._vehicle(child, f"/campaign/vehicles/{len(found)}"))
        if channels:
            out["channels"] = channels
        out["vehicles"] = found
        return out

    def _channel(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        name, settings = node.children
        assert isinstance(name, Token)
        self._mark(ptr, node)
        self._mark(ptr + "/name", name)
        return {"name": _word(name), **self._settings(settings, ptr, CHANNEL_SETTINGS)}

    def _vehicle(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        name, rest = node.children[0], node.children[1:]
        assert isinstance(name, Token)
        self._mark(ptr, node)
        self._mark(ptr + "/name", name)
        out: dict[str, Any] = {"name": _word(name)}
        devices: list[dict[str, Any]] = []
        for child in rest:
            assert isinstance(child, Tree)
            part = str(child.data)
            if part == "description":
                out["description"] = _unquote(child.children[0])  # type: ignore[arg-type]
            elif part == "vehicle_channel":
                self._mark(ptr + "/channel", child)
                out["channel"] = str(child.children[0])
            elif part == "vehicle_device":
                sensor, path = child.children
                at = f"{ptr}/devices/{len(devices)}"
                self._mark(at, child)
                self._mark(at + "/sensor", sensor)
                devices.append({"sensor": str(sensor), "path": _word(path.children[0])})  # type: ignore[union-attr, arg-type]
            elif part == "link":
                self._mark(ptr + "/link", child)
                known = LINK_SETTINGS | RADIO_SETTINGS
                out["link"] = _nest(self._settings(child.children[0], ptr + "/link", known))
            else:
                key = "pubBroker" if part == "vehicle_pub" else "subBroker"
                out[key] = self._vehicle_broker(child, f"{ptr}/{key}")
        if devices:
            out["devices"] = devices
        order = ["name", "description", "channel", "pubBroker", "subBroker", "devices", "link"]
        return {k: out[k] for k in order if k in out}

    def _vehicle_broker(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        self._mark(ptr, node)
        endpoint = node.children[0]
        assert isinstance(endpoint, Tree)
        out: dict[str, Any] = {"endpoint": self._endpoint(endpoint, ptr + "/endpoint")}
        if len(node.children) > 1:
            path = node.children[1]
            assert isinstance(path, Tree)
            out["path"] = _word(path.children[0])  # type: ignore[arg-type]
        return out

    def _endpoint(self, node: Tree[Token], ptr: str) -> dict[str, Any]:
        host, port = node.children
        assert isinstance(host, Token) and isinstance(port, Token)
        self._mark(ptr, node)
        self._mark(ptr + "/host", host)
        self._mark(ptr + "/port", port)
        return {"host": _word(host), "port": self._int(port, ptr + "/port")}

    def _broker(self, node: Tree[Token], ptr: str, path_key: str) -> dict[str, Any]:
        broker: dict[str, Any] = {}
        self._mark(ptr, node)
        for child in node.children:
            assert isinstance(child, Tree)
            if child.data == "broker_name":
                tok = child.children[0]
                assert isinstance(tok, Token)
                broker["name"] = _word(tok)
                self._mark(ptr + "/name", tok)
            elif child.data == "path":
                tok = child.children[0]
                assert isinstance(tok, Token)
                broker[path_key] = _word(tok)
                self._mark(f"{ptr}/{path_key}", tok)
            elif child.data == "endpoint":
                broker["endpoint"] = self._endpoint(child, ptr + "/endpoint")
            elif ptr == "/pubBroker":
                broker["ingress"] = self._settings(child, ptr + "/ingress", INGRESS_SETTINGS)
                self._mark(ptr + "/ingress", child)
            else:
                self._error(child, "the SubBroker takes no settings block", ptr)
        order = ["name", "endpoint", path_key, "ingress"]
        return {k: broker[k] for k in order if k in broker}

    def _settings(
        self, node: Tree[Token] | Token, ptr: str, known: dict[str, tuple[str, str]]
    ) -> dict[str, Any]:
        out: dict[str, Any] = {}
        assert isinstance(node, Tree)
        for setting in node.children:
            assert isinstance(setting, Tree)
            key_tok, value = setting.children
            assert isinstance(key_tok, Token) and isinstance(value, Tree)
            key = str(key_tok)
            if key not in known:
                self._error(
                    key_tok, f"unknown setting {key!r}; expected one of {', '.join(known)}", ptr
                )
                continue
            prop, kind = known[key]
            self._mark(f"{ptr}/{prop}", setting)
            if prop in out:
                self._error(key_tok, f"setting {key!r} given twice", f"{ptr}/{prop}")
            out[prop] = self._setting_value(value, kind, key, f"{ptr}/{prop}")
        return {k: out[k] for _, (k, _) in known.items() if k in out}

    def _setting_value(self, value: Tree[Token], kind: str, key: str, ptr: str) -> Any:
        tok = value.children[0]
        assert isinstance(tok, Token)
        found = {"number": "decimal", "string": "string", "word": "word"}[str(value.data)]
        if kind == "bool" and found == "word" and str(tok) in ("true", "false"):
            return str(tok) == "true"
        if kind == "int" and found == "decimal":
            return self._int(tok, ptr)
        if kind != found:
            wanted = {
                "decimal": "a number",
                "int": "a whole number",
                "string": "a string",
                "word": "a name",
                "bool": "true or false",
            }[kind]
            self._error(tok, f"setting {key!r} takes {wanted}", ptr)
            return None
        if kind == "string":
            return _unquote(tok)
        if kind == "decimal":
            return self._decimal(tok)
        return str(tok)

    def _publisher(self, node: Tree[Token], index: int) -> dict[str, Any]:
        ptr = f"/publishers/{index}"
        name = node.children[0]
        assert isinstance(name, Token)
        self._mark(ptr, node)
        self._mark(ptr + "/name", name)
        pub: dict[str, Any] = {"name": _word(name)}
        topics: list[str] = []
        for child in node.children[1:]:
            if isinstance(child, Tree) and child.data == "endpoint":
                pub["endpoint"] = self._endpoint(child, ptr + "/endpoint")
            elif isinstance(child, Token) and child.type == "NUMBER":
                pub["periodS"] = self._decimal(child, ptr + "/periodS")
                self._mark(ptr + "/periodS", child)
            else:
                self._mark(f"{ptr}/topics/{len(topics)}", child)
                topics.append(_topic(child))
        pub["topics"] = topics
        return pub

    def _alert(self, node: Tree[Token], ptr: str) -> list[str]:
        """``alert = scientist + operator``: the roles whose views show the alert
        (each once; an unknown role is an error at its word)."""
        roles: list[str] = []
        for k, word in enumerate(node.children):
            assert isinstance(word, Token)
            self._mark(f"{ptr}/{k}", word)
            if str(word) not in ALERT_ROLES or str(word) in roles:
                what = "twice" if str(word) in roles else "unknown"
                self._error(
                    word,
                    f"alert: role {str(word)!r} {what}; expected some of {' + '.join(ALERT_ROLES)}",
                    f"{ptr}/{k}",
                )
            roles.append(str(word))
        self._mark(ptr, node)
        return roles

    def _subscriber(self, node: Tree[Token], index: int) -> dict[str, Any]:
        ptr = f"/subscribers/{index}"
        name = node.children[0]
        assert isinstance(name, Token)
        self._mark(ptr, node)
        self._mark(ptr + "/name", name)
        sub: dict[str, Any] = {"name": _word(name)}
        for child in node.children[1:]:
            if isinstance(child, Tree) and child.data == "endpoint":
                sub["endpoint"] = self._endpoint(child, ptr + "/endpoint")
            elif isinstance(child, Tree) and child.data == "backfill":
                word = child.children[0]
                assert isinstance(word, Token)
                self._mark(ptr + "/backfill", word)
                if str(word) not in BACKFILL_POLICIES:
                    self._error(
                        word,
                        f"unknown backfill policy {str(word)!r}; expected one of "
                        f"{', '.join(BACKFILL_POLICIES)}",
                        ptr + "/backfill",
                    )
                sub["backfill"] = str(word)
            elif isinstance(child, Tree) and child.data == "agg_args":
                sub.update(self._agg_args(child, sub.get("aggregation", ""), ptr))
            elif isinstance(child, Tree) and child.data == "agg_param":
                key, value = child.children
                assert isinstance(key, Token) and isinstance(value, Token)
                self._mark(f"{ptr}/{key}", value)
                sub[str(key)] = str(value) if value.type == "NAME" else float(value)
            elif isinstance(child, Tree) and child.data == "max_events":
                number = child.children[0]
                assert isinstance(number, Token)
                sub["maxEvents"] = self._int(number, ptr + "/maxEvents")
                self._mark(ptr + "/maxEvents", number)
            elif isinstance(child, Tree) and child.data == "alert":
                sub["alert"] = self._alert(child, ptr + "/alert")
            elif isinstance(child, Tree) and child.data == "resolution":
                number = child.children[0]
                assert isinstance(number, Token)
                self._mark(ptr + "/resolution", number)
                sub["resolution"] = float(number)
            elif isinstance(child, Tree) or child.type == "STRING":
                sub["topic"] = _topic(child)
                self._mark(ptr + "/topic", child)
            elif child.type == "NUMBER":
                sub["periodS"] = self._decimal(child, ptr + "/periodS")
                self._mark(ptr + "/periodS", child)
            else:
                self._mark(ptr + "/aggregation", child)
                if str(child) not in AGGREGATIONS:
                    self._error(
                        child,
                        f"unknown aggregation {str(child)!r}; expected one of "
                        f"{', '.join(AGGREGATIONS)}",
                        ptr + "/aggregation",
                    )
                sub["aggregation"] = str(child)
        return sub


def _split_condition(
    nodes: list[Tree[Token] | Token],
) -> tuple[list[Tree[Token] | Token], Tree[Token] | None]:
    """A source's ``scale``/``offset`` apart from its ``where`` (last, when given)."""
    if nodes and isinstance(nodes[-1], Tree) and "condition" in str(nodes[-1].data):
        return nodes[:-1], nodes[-1]
    return nodes, None


def _qualify_topics(doc: dict[str, Any]) -> None:
    """Topics written short (``accel_x`` or ``accelerometer.accel_x``, as a
    reference in the original tool may be) get their full name when exactly
    one variable of the drone has that name; anything else is left for the
    validator to report (unknown topic)."""
    drone = doc.get("drone")
    if not drone:
        return
    by_short: dict[str, list[str]] = {}
    for sensor in drone.get("sensors", []):
        for var in sensor.get("variables", []):
            name = f"{drone['name']}.{sensor['name']}.{var['name']}"
            by_short.setdefault(var["name"], []).append(name)
            by_short.setdefault(f"{sensor['name']}.{var['name']}", []).append(name)

    def full(topic: str) -> str:
        found = by_short.get(topic, []) if topic.count(".") < 2 else []
        return found[0] if len(found) == 1 else topic

    for pub in doc["publishers"]:
        pub["topics"] = [full(t) for t in pub.get("topics", [])]
    for sub in doc["subscribers"]:
        if "topic" in sub:
            sub["topic"] = full(sub["topic"])


_BLOCK_WORD = {
    "drone": "Drone",
    "pubbroker": "PubBroker",
    "subbroker": "SubBroker",
    "link": "Link",
    "campaign": "Campaign",
}
_TOP_ORDER = [
    "schemaVersion",
    "drone",
    "pubBroker",
    "subBroker",
    "link",
    "publishers",
    "subscribers",
    "campaign",
    "layout",
]


def _ordered(doc: dict[str, Any]) -> dict[str, Any]:
    return {k: doc[k] for k in _TOP_ORDER if k in doc}


__all__ = ["parse_text", "SourceMap", "pointer_join"]


def _nest(settings: dict[str, Any]) -> dict[str, Any]:
    """Settings whose property is ``outer/inner`` gathered into ``outer``
    (the radio profile inside the link), in order."""
    out: dict[str, Any] = {}
    for prop, value in settings.items():
        outer, _, inner = prop.partition("/")
        if inner:
            out.setdefault(outer, {})[inner] = value
        else:
            out[prop] = value
    return out
