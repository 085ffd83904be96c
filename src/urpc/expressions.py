"""Plain arithmetic in YAML values: ``5/12``, ``pi/4``, ``2*1e-3``, ``10**-2``.

Input files may write numbers as expressions so that values such as the paper's ``I2 = 5/12``
read as they are published. Only numbers, ``pi`` and ``+ - * / **`` are accepted; nothing is
executed.
"""

from __future__ import annotations

import ast
import math
import operator

_OPS = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
    ast.Pow: operator.pow, ast.USub: operator.neg, ast.UAdd: operator.pos,
}  # fmt: skip


def evaluate(text: str) -> float:
    """The value of an arithmetic expression.

    Raises:
        ValueError: anything else than numbers, ``pi`` and ``+ - * / **``, a division by zero,
            an overflow, or a non-finite result.
    """

    def ev(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](ev(node.operand))
        raise ValueError(f"'{text}' is not plain arithmetic")

    try:
        value = ev(ast.parse(text.strip(), mode="eval"))
    except (SyntaxError, ZeroDivisionError, OverflowError, TypeError) as exc:
        raise ValueError(f"'{text}' is not plain arithmetic ({exc})") from None
    if not math.isfinite(value):
        raise ValueError(f"'{text}' is not finite")
    return value
