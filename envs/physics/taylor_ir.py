"""The Taylor recurrences compiled by emitting their machine code directly.

numba types and lowers each of the recurrences' ~3,000 additions and products on its own,
a large part of a cold first step (measured: ``docs/MAINTAINERS.md``).
:func:`compile_as_emitted` gives the generated ``recurrences`` a compiled form that writes
the same operations (:func:`roller_gym.physics.taylor.program`), in the same order, as LLVM
instructions in one step: the same bits (IEEE operations, no reassociation or contraction),
in a fraction of the time. Interpreted (``NUMBA_DISABLE_JIT``), the Python function runs.
"""

from __future__ import annotations

import ast
import operator
from collections.abc import Callable

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload
from roller_gym.physics.taylor import INPUTS, program

__all__ = ["compile_as_emitted"]

_DOUBLE = ir.DoubleType()
#: Python's arithmetic on two numbers, as CPython folds constant sub-expressions, and the
#: instruction numba lowers it to (``error_model="numpy"``: a division is not checked).
_OPS = {ast.Add: (operator.add, "fadd"), ast.Sub: (operator.sub, "fsub"),
        ast.Mult: (operator.mul, "fmul"), ast.Div: (operator.truediv, "fdiv")}


def _emit(builder: ir.IRBuilder, node: ast.expr, env: dict) -> ir.Value | float:
    """The value of the expression ``node``: a Python float where CPython's compiler folds
    it to a constant, else an instruction (as numba lowers it)."""
    if isinstance(node, ast.Name):
        return env[node.id]
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        value = _emit(builder, node.operand, env)
        if isinstance(value, float):
            return -value
        return builder.fsub(ir.Constant(_DOUBLE, -0.0), value)  # numba's negation
    if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
        fold, name = _OPS[type(node.op)]
        left, right = _emit(builder, node.left, env), _emit(builder, node.right, env)
        if isinstance(left, float) and isinstance(right, float):
            return fold(left, right)
        args = [ir.Constant(_DOUBLE, v) if isinstance(v, float) else v for v in (left, right)]
        return getattr(builder, name)(*args)
    raise ValueError(f"the recurrences hold an expression that is not emitted: "
                     f"{ast.dump(node)}")


def compile_as_emitted(recurrences: Callable, order: int) -> None:
    """Register the compiled form of ``recurrences`` (the generated function of
    :data:`~roller_gym.physics.taylor.INPUTS`, returning (X[0..order], V[0..order],
    (ST0, CT0, SQ0, CQ0))): :func:`~roller_gym.physics.taylor.program` emitted as LLVM
    instructions."""
    steps = [(name, ast.parse(expr, mode="eval").body) for name, expr in program(order)]
    series = types.UniTuple(types.float64, order + 1)
    result = types.Tuple((series, series, types.UniTuple(types.float64, 4)))

    @intrinsic
    def emitted(typingctx, values):
        if values != types.UniTuple(types.float64, len(INPUTS)):
            return None

        def codegen(context, builder, signature, args):
            env = dict(zip(INPUTS, cgutils.unpack_tuple(builder, args[0]), strict=True))
            for name, node in steps:
                value = _emit(builder, node, env)
                env[name] = ir.Constant(_DOUBLE, value) if isinstance(value, float) else value

            def pack(typ, names):
                return context.make_tuple(builder, typ, [env[n] for n in names])

            return context.make_tuple(builder, result, [
                pack(series, [f"X{n}" for n in range(order + 1)]),
                pack(series, [f"V{n}" for n in range(order + 1)]),
                pack(result.types[2], ["ST0", "CT0", "SQ0", "CQ0"])])

        return result(values), codegen

    # the typing function and the implementation take the generated function's arguments
    names = ", ".join(INPUTS)
    namespace = {"__name__": __name__, "emitted": emitted, "types": types}
    exec(f"def compiled({names}):\n"
         f"    return emitted(({names},))\n"
         f"def typing({names}):\n"
         f"    if all(isinstance(a, types.Float) for a in ({names},)):\n"
         f"        return compiled\n", namespace)
    overload(recurrences, jit_options={"error_model": "numpy"})(namespace["typing"])
