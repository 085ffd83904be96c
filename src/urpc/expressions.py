"""Plain arithmetic in YAML values: ``5/12``, ``pi/4``, ``2*1e-3``, ``10**-2``.

Input files may write numbers as expressions so that values such as the paper's ``I2 = 5/12``
read as they are published. Only numbers, ``pi`` and ``+ - * / **`` are accepted; nothing is
executed.
"""

from __future__ import annotations

import ast
import math
import operator

#: The largest finite double, for the overflow message.
LARGEST = 1.7976931348623157e308


class ExpressionOverflow(ValueError):
    """An expression whose value (or an intermediate value) is beyond the largest double."""


_OPS = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
    ast.Pow: operator.pow, ast.USub: operator.neg, ast.UAdd: operator.pos,
}  # fmt: skip


def evaluate(text: str) -> float:
    """The value of an arithmetic expression.

    Raises:
        ExpressionOverflow: a number or a result beyond the largest double (``1e309``,
            ``10**10**10``, ``1e200 * 1e200``); a :class:`ValueError` whose message says so.
        ValueError: anything else than numbers, ``pi`` and ``+ - * / **``, a division by zero,
            or a complex result.
    """

    def overflow() -> ExpressionOverflow:
        return ExpressionOverflow(
            f"'{text}' overflows: its value is beyond the largest double ({LARGEST:.4g})"
        )

    def ev(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            try:
                value = float(node.value)
            except OverflowError:  # an integer literal beyond the largest double
                raise overflow() from None
            if not math.isfinite(value):  # a float literal such as 1e309 reads as inf
                raise overflow()
            return value
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.operand))
        raise ValueError(f"'{text}' is not plain arithmetic")

    try:
        value = ev(ast.parse(text.strip(), mode="eval"))
    except OverflowError:  # float ** float beyond the largest double
        raise overflow() from None
    except (SyntaxError, ZeroDivisionError, TypeError) as exc:
        raise ValueError(f"'{text}' is not plain arithmetic ({exc})") from None
    if isinstance(value, complex):  # (-8) ** (1/3)
        raise ValueError(f"'{text}' is not a real number")
    if not math.isfinite(value):  # 1e200 * 1e200: IEEE overflow to inf, no exception
        raise overflow()
    return value
