"""The values the file formats are made of: numbers written as plain arithmetic, vectors, names,
values of several forms (:func:`either`) and the interval notations of uncertainty boxes
(``[lo, hi]``, ``10%``, ``+-0.05``, ...).

Each is an annotated type: a validator that parses what YAML gives (numbers, or text that
:func:`urpc.expressions.evaluate` reads) with one clear message, and the JSON Schema of the
accepted input, so that editors accept ``5/12`` or ``10%`` where a number or an interval goes.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    Discriminator,
    Tag,
    ValidationInfo,
    WithJsonSchema,
)

from ..expressions import ExpressionOverflow, evaluate

#: Plain arithmetic as text: numbers, ``pi``, ``+ - * / **`` and parentheses (``5/12``, ``1e-3``).
EXPRESSION_PATTERN = r"^[-+*/().0-9eEpi\s]+$"
EXPRESSION_SCHEMA = {
    "type": "string",
    "pattern": EXPRESSION_PATTERN,
    "description": "plain arithmetic: numbers, pi, + - * / ** and parentheses (5/12, pi/4, 1e-3)",
}


def finite_number(value: Any) -> float | None:
    """The value of a number or of an arithmetic text, ``None`` if it is neither or not finite.

    Raises:
        ExpressionOverflow: a text whose value is beyond the largest double (``1e309``): its
            message says so, which "not a finite number" would hide.
    """
    if isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        number = float(value)
    elif isinstance(value, str):
        try:
            number = evaluate(value)
        except ExpressionOverflow:
            raise
        except ValueError:
            return None
    else:
        return None
    return number if math.isfinite(number) else None


def _number_type(bound: str | None, unit: str, keyword: str | None = None) -> Any:
    """A finite number, optionally ``> 0`` (``bound=">"``) or ``>= 0`` (``">="``), in ``unit``;
    with ``keyword``, that word too, read as ``None`` (``continuous``, ``unknown``, ``none``)."""
    limit = f" {bound} 0" if bound else ""
    expected = f"a number{limit}" + (f" [{unit}]" if unit else "")
    alternative = f" or '{keyword}'" if keyword else ""

    def check(value: Any, info: ValidationInfo) -> float | None:
        if keyword is not None and isinstance(value, str) and value.strip().lower() == keyword:
            return None
        number = finite_number(value)
        if number is None:
            raise ValueError(f"{value!r} is not a finite number; expected {expected}{alternative}")
        if (bound == ">" and number <= 0) or (bound == ">=" and number < 0):
            name = info.field_name or "the value"
            raise ValueError(f"{name} must be{limit} [{unit}]{alternative}; got {value!r}")
        return number

    number_schema: dict[str, Any] = {"type": "number"}
    if bound:
        number_schema["exclusiveMinimum" if bound == ">" else "minimum"] = 0
    forms = [number_schema, EXPRESSION_SCHEMA] + ([{"const": keyword}] if keyword else [])
    return Annotated[
        float | None if keyword else float,
        BeforeValidator(check),
        WithJsonSchema({"anyOf": forms}),
    ]


#: A finite number, or plain arithmetic text.
Number = _number_type(None, "")


def Positive(unit: str, keyword: str | None = None) -> Any:
    """A number > 0 in ``unit`` (or ``keyword``, read as ``None``)."""
    return _number_type(">", unit, keyword)


def NonNegative(unit: str, keyword: str | None = None) -> Any:
    """A number >= 0 in ``unit`` (or ``keyword``, read as ``None``)."""
    return _number_type(">=", unit, keyword)


def _integer_type(minimum: int) -> Any:
    def check(value: Any) -> int:
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise ValueError(f"{value!r} is not an integer >= {minimum}")
        return value

    return Annotated[
        int, BeforeValidator(check), WithJsonSchema({"type": "integer", "minimum": minimum})
    ]


#: An integer >= 0 (a seed).
Count = _integer_type(0)
#: An integer >= 1.
PositiveCount = _integer_type(1)


def _list_of(length: int | None, example: str) -> Any:
    def check(value: Any) -> Any:
        if not isinstance(value, list | tuple) or not value:
            raise ValueError(f"{value!r} is not a list of numbers; expected e.g. {example}")
        if length is not None and len(value) != length:
            raise ValueError(f"{value!r} is not a list of {length} numbers")
        return value

    return BeforeValidator(check)


#: A non-empty list of numbers (one per joint, ...).
Vector = Annotated[tuple[Number, ...], _list_of(None, "[0.1, -0.2]")]
#: Three numbers (a position [m] or roll-pitch-yaw angles [rad]).
Vector3 = Annotated[tuple[Number, Number, Number], _list_of(3, "[0, 0, 0.1]")]


def _text(value: Any) -> str:
    if isinstance(value, bool) or not isinstance(value, str | int | float):
        raise ValueError(f"{value!r} is not a text")
    return str(value)


#: Free text (numbers are read as their text).
Text = Annotated[str, BeforeValidator(_text), WithJsonSchema({"type": ["string", "number"]})]


def _form(value: Any) -> str:
    if isinstance(value, list | tuple):
        return "list"
    # A model is a mapping once validated (when the value is serialized).
    return "mapping" if isinstance(value, Mapping | BaseModel) else "scalar"


def either(expected: str, scalar: Any = None, mapping: Any = None, array: Any = None) -> Any:
    """The forms of one value told apart by its YAML type (a text or number, a mapping, a list),
    so that a wrong value gets the one message of the form it has."""
    forms = {"scalar": scalar, "mapping": mapping, "list": array}
    members = tuple(Annotated[kind, Tag(tag)] for tag, kind in forms.items() if kind is not None)
    return Annotated[
        Union[members],  # noqa: UP007 - built from a tuple
        Discriminator(_form, custom_error_type="form", custom_error_message=f"expected {expected}"),
    ]


# ---------------------------------------------------------------------------- intervals
INTERVAL_HELP = (
    "an interval [lo, hi], a relative width '10%', an offset '+-0.05', or a one-sided range "
    "such as [0%, +100%] or ['+0', '+0.025']"
)


@dataclass(frozen=True)
class End:
    """One end of an interval, given absolutely or relative to the nominal value ``x0``.

    ``form``: ``absolute`` (``value``), ``percent`` (``x0 (1 + value/100)``), ``offset``
    (``x0 + value``) or ``width`` (``x0 + |x0| value``, the ends of ``10%``).
    """

    form: Literal["absolute", "percent", "offset", "width"]
    value: float

    def at(self, nominal: float) -> float:
        if self.form == "absolute":
            return self.value
        if self.form == "percent":
            return nominal * (1.0 + self.value / 100)
        if self.form == "offset":
            return nominal + self.value
        return nominal + abs(nominal) * self.value


@dataclass(frozen=True)
class Interval:
    """An interval entry as written (``text``), resolved against a nominal by :meth:`around`."""

    lower: End
    upper: End
    text: str

    @property
    def absolute(self) -> bool:
        return self.lower.form == self.upper.form == "absolute"

    def vanishes_at(self, nominal: float) -> bool:
        """Whether a relative width (``10%``, ``[-5%, +5%]``) collapses to nothing because the
        nominal it is relative to is 0 (a width the writer meant, which is not there)."""
        return nominal == 0 and any(
            end.form in ("percent", "width") and end.value != 0 for end in (self.lower, self.upper)
        )

    def around(self, nominal: float | None) -> tuple[float, float]:
        """``(lo, hi)`` around ``nominal`` (``None``: only absolute forms are allowed).

        Raises:
            ValueError: a relative form without a nominal, a non-finite end, or lo > hi.
        """
        if nominal is None and not self.absolute:
            raise ValueError(
                f"{self.text} is relative, but this field has no nominal to be relative to; "
                f"expected {INTERVAL_HELP}"
            )
        lo, hi = self.lower.at(nominal), self.upper.at(nominal)
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError(f"{self.text} has a non-finite end; expected {INTERVAL_HELP}")
        if lo > hi:
            raise ValueError(
                f"lower end {lo:.6g} is greater than upper end {hi:.6g}; write [lo, hi] with "
                "lo <= hi"
            )
        return float(lo), float(hi)


def _number_or_fail(text: Any, raw: Any, what: str) -> float:
    # numpy's scalars (np.int64 from an array, np.float32) are numbers too; a flag is not
    if isinstance(text, np.integer | np.floating):
        text = text.item()
    if isinstance(text, str | int | float) and not isinstance(text, bool):
        try:
            return float(text) if not isinstance(text, str) else evaluate(text)
        except ExpressionOverflow as exc:  # "'1e309' overflows: ...", not "not a number"
            raise ValueError(f"{exc}; expected {what}") from None
        except ValueError:
            pass
    raise ValueError(f"{raw!r} is not a number; expected {what}")


def _end(item: Any) -> End:
    if isinstance(item, str):
        text = item.strip()
        if text.endswith("%"):
            return End("percent", _number_or_fail(text[:-1], item, "a percentage"))
        if text[:1] in "+-" and not text.startswith("+-"):
            return End("offset", _number_or_fail(text, item, "an offset"))
    return End("absolute", _number_or_fail(item, item, INTERVAL_HELP))


def parse_interval(value: Any) -> Interval:
    """The :class:`Interval` of one entry of an uncertainty box.

    Raises:
        ValueError: not one of the forms of :data:`INTERVAL_HELP`.
    """
    if isinstance(value, Interval):
        return value
    if isinstance(value, list | tuple):
        if len(value) != 2:
            raise ValueError(f"{value!r} has {len(value)} entries, not 2; expected {INTERVAL_HELP}")
        interval = Interval(_end(value[0]), _end(value[1]), repr(list(value)))
    elif isinstance(value, str) and value.strip().endswith("%"):
        text = value.strip()[:-1].strip()
        fraction = _number_or_fail(text.removeprefix("+-"), value, "a percentage") / 100
        if fraction < 0:
            raise ValueError(f"{value!r} is a negative width; expected {INTERVAL_HELP}")
        interval = Interval(End("width", -fraction), End("width", fraction), repr(value))
    elif isinstance(value, str) and value.strip().startswith("+-"):
        width = _number_or_fail(value.strip()[2:], value, "an offset")
        if width < 0:
            raise ValueError(f"{value!r} is a negative width; expected {INTERVAL_HELP}")
        interval = Interval(End("offset", -width), End("offset", width), repr(value))
    elif isinstance(value, int | float | str) and not isinstance(value, bool):
        number = _number_or_fail(value, value, INTERVAL_HELP)
        interval = Interval(End("absolute", number), End("absolute", number), repr(value))
    else:
        raise ValueError(f"{value!r} is not an interval; expected {INTERVAL_HELP}")
    if interval.absolute:
        interval.around(None)  # non-finite ends and lo > hi are known now
    return interval


_INTERVAL_END = {
    "anyOf": [
        {"type": "number"},
        {
            "type": "string",
            "pattern": r"^\s*([-+*/().0-9eEpi\s]+%?)\s*$",
            "description": "a number or plain arithmetic; 'x%' (nominal (1 + x/100)) or '+x', "
            "'-x' (nominal + x) relative to the nominal",
        },
    ]
}
#: One entry of an uncertainty box (see :data:`INTERVAL_HELP` and ``docs/uncertainty-format.md``).
IntervalEntry = Annotated[
    Interval,
    BeforeValidator(parse_interval),
    WithJsonSchema(
        {
            "description": INTERVAL_HELP + "; a single number is an exact value",
            "anyOf": [
                {"type": "array", "items": _INTERVAL_END, "minItems": 2, "maxItems": 2},
                {"type": "number"},
                {
                    "type": "string",
                    "pattern": r"^\s*(\+-)?[-+*/().0-9eEpi\s]+%?\s*$",
                    "description": "'10%' or '+-10%' (nominal +- 10 % of its magnitude), "
                    "'+-0.05' (nominal +- 0.05), or an exact value as plain arithmetic",
                },
            ],
        }
    ),
]
