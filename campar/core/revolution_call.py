"""The chain and the orbit tracer call one revolution through its machine-code address.

numba compiles a callee while it types the caller, and links the callee's code into
the caller's module, where LLVM optimises it and turns it into machine code again. For
``run_revolution`` (the integrator, the field and the events under it: a large part of
the kernel's compile) a direct call means a cold chain compile cannot type past the first
revolution before the revolution is compiled, and then compiles it twice.
Called through an address (``call_revolution``), the chain types against the
revolution's signature alone: it compiles while a forked helper compiles the
revolution (campar.core.split_compile), and its module holds none of the revolution's
code. One indirect call a revolution costs nothing measurable beside the revolution.

The orbit tracer (``tracer.trace_compiled``) calls the revolution with a recorder, a
variant of its own, the same way: a forked helper compiles that variant too.

The address is a run-time argument (``ChainWork.revolution``, the tracer's ``link``), so
a cached entry holds no address of this process. ``revolution_link`` compiles or loads
the revolution for the signature the caller calls it with, computed here from the
caller's arguments; every call checks a fingerprint of that signature against the one
the caller was typed with and raises if they differ (a drift between the two would
otherwise call code with the wrong arguments).
"""

import zlib

import numpy as np
from numba import typeof, types
from numba.core import cgutils
from numba.extending import intrinsic

from .model import PAPER_LAW, kernel_law, make_params
from .revolution import run_revolution, scale_solver_options

VECTOR = types.Array(types.float64, 1, "C")  # the state, its derivative, a statistics row
MODE = types.Array(types.int64, 1, "C")


def fingerprint(args) -> int:
    """A signature's argument types as a number both sides of the call compute alike."""
    return zlib.crc32(repr(tuple(args)).encode())


def revolution_args(solver, cs, work, recorder=types.none, law=PAPER_LAW) -> tuple:
    """run_revolution's argument types as the chain (transient.step_revolution) and the orbit
    tracer call it, with the step buffers ``work``, a recorder of type ``recorder`` (the
    chain's: none) and the job's ``law`` (model.kernel_law): the cell's parameters and
    options are the types make_params and scale_solver_options return for float64
    parameters and that law."""
    rk4_steps = typeof(cs)[cs._fields.index("rk4_steps")]
    params = _return_type(make_params, (types.float64,) * 5 + (typeof(kernel_law(law)),))
    options = _return_type(scale_solver_options, (typeof(solver), types.float64, rk4_steps))
    return (
        VECTOR,
        VECTOR,
        params,
        options,
        typeof(work),
        MODE,
        VECTOR,
        types.int64,
        types.int64,
        recorder,
    )


def _return_type(dispatcher, args: tuple) -> types.Type:
    """What ``dispatcher`` returns for these argument types (compiled or loaded if need be)."""
    dispatcher.compile(args)
    return dispatcher.overloads[args].signature.return_type


_LINKS: dict = {}  # (solver options' type, recorder type, law type) -> (address, fingerprint)


def _link(args: tuple) -> tuple[int, int]:
    run_revolution.compile(args)
    compiled = run_revolution.overloads[args]
    if compiled.signature.return_type != types.int64:
        raise TypeError(f"run_revolution returns {compiled.signature.return_type}, not int64")
    address = compiled.library.get_pointer_to_function(compiled.fndesc.llvm_func_name)
    return address, fingerprint(args)


def revolution_link(solver, cs, work, recorder=types.none, law=PAPER_LAW) -> np.ndarray:
    """int64 [address, fingerprint] of run_revolution compiled (or loaded) for the call
    ``revolution_args`` describes: what ``call_revolution`` takes. Kept by the types of the
    solver options and the law, the argument types that differ between jobs
    (kernel.chain_loaded): a chain looks its link up by those types instead of typing every
    argument, and the fingerprint every call checks would catch any other
    argument type changing."""
    key = (typeof(solver), recorder, typeof(kernel_law(law)))
    if key not in _LINKS:
        _LINKS[key] = _link(revolution_args(solver, cs, work, recorder, law))
    return np.array(_LINKS[key], dtype=np.int64)


@intrinsic
def call_revolution(typingctx, link, x, f, p, opt, w, mode, row, stats, step_limit, rec):
    """run_revolution(x, f, p, opt, w, mode, row, stats, step_limit, rec) through
    ``link`` (revolution_link): its status. Literal arguments are passed as their plain
    types, the ones revolution_args names."""
    args = tuple(types.unliteral(a) for a in (x, f, p, opt, w, mode, row, stats, step_limit, rec))
    expected = fingerprint(args)

    def codegen(context, builder, signature, llargs):
        link_array = context.make_array(signature.args[0])(context, builder, llargs[0])
        address = builder.load(cgutils.gep(builder, link_array.data, 0))
        linked = builder.load(cgutils.gep(builder, link_array.data, 1))
        mismatch = builder.icmp_unsigned("!=", linked, linked.type(expected))
        with cgutils.if_unlikely(builder, mismatch):
            context.call_conv.return_user_exc(
                builder,
                RuntimeError,
                (
                    "run_revolution is called with other argument types than it was linked for "
                    "(campar.core.revolution_call.revolution_args has drifted from the call)",
                ),
            )
        function_type = context.call_conv.get_function_type(types.int64, args)
        callee = builder.inttoptr(address, function_type.as_pointer())
        status, result = context.call_conv.call_function(
            builder, callee, types.int64, args, list(llargs[1:])
        )
        with cgutils.if_unlikely(builder, status.is_error):
            context.call_conv.return_status_propagate(builder, status)
        return result

    return types.int64(link, *args), codegen
