"""Whether the kernel can be compiled ahead of time: numba.pycc, the paper's law, one chain.

    python benchmarks/aot_kernel.py [--dir DIR]

Builds a CPython extension holding ``campar.core.kernel.chain_compiled`` for the paper's
law with the default solver and label outputs, and ``run_revolution`` for the same
arguments, whose address an exported function returns (the chain calls its revolution
through an address: campar.core.revolution_call). Then, in a fresh process, imports it,
says whether numba was imported with it, and runs two chains of 200 cells through it and
through ``run_chain`` (numba's cache), comparing every output array bit for bit and
timing both. What it measures is the start-up lever of #38 item 4: a kernel that a run
can call without importing numba or loading its cache. numba.pycc is deprecated; numba
0.68 still ships it.
"""

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MODULE = "campar_aot_probe"
CHAINS = ((3.0, 0.8), (6.0, 0.9))  # (first ω, μcn) of each chain, ω down to 1
CELLS = 200


def settings(mu_cn: float = 0.8):
    from campar.core.model import kernel_law
    from campar.model.compute import cell_settings, model_law, output_bits, solver_options
    from campar.model.model import Model

    model = Model.build({"omega": 2.0, "f0": 0.5, "mu_kn": 0.8, "mu_cn": mu_cn})
    outputs = output_bits(("label",))
    return kernel_law(model_law(model)), solver_options(model), cell_settings(model, outputs)


def build(directory: Path) -> None:
    import numpy as np
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic
    from numba.pycc import CC

    from campar.core.kernel import chain_compiled, chain_signature, make_chain_work
    from campar.core.revolution import run_revolution
    from campar.core.revolution_call import fingerprint, revolution_args
    from campar.model.compute import output_bits
    from campar.sweep.tile import allocate_outputs

    law, solver, cs = settings()
    out = allocate_outputs(1, output_bits(("label",)), 0)
    chain_types = chain_signature(law, np.zeros(2), solver, cs, out)
    revolution_types = revolution_args(solver, cs, make_chain_work(cs).w6, law=law)

    @intrinsic
    def revolution_pointer(typingctx):
        def codegen(context, builder, signature, llargs):
            compiled = context.compile_subroutine(
                builder, run_revolution.py_func, types.int64(*revolution_types)
            )
            fnty = context.call_conv.get_function_type(types.int64, revolution_types)
            name = compiled.fndesc.llvm_func_name
            function = cgutils.get_or_insert_function(builder.module, fnty, name)
            return builder.ptrtoint(function, context.get_value_type(types.int64))

        return types.int64(), codegen

    def revolution_address():
        return revolution_pointer()

    cc = CC(MODULE)
    cc.output_dir = str(directory)
    cc.export("chain", types.none(*chain_types))(chain_compiled.py_func)
    cc.export("revolution_address", types.int64())(revolution_address)
    start = time.perf_counter()
    cc.compile()
    print(f"built {MODULE} in {time.perf_counter() - start:.1f} s")
    (directory / "fingerprint").write_text(str(fingerprint(revolution_types)))


def compare(directory: Path) -> None:
    sys.path.insert(0, str(directory))
    start = time.perf_counter()
    aot = __import__(MODULE)
    address = aot.revolution_address()
    print(
        f"import and address: {1e3 * (time.perf_counter() - start):.2f} ms; "
        f"numba imported: {'numba' in sys.modules}"
    )
    import numpy as np

    from campar.core.kernel import make_chain_work, run_chain
    from campar.core.model import start_chain
    from campar.model.compute import output_bits
    from campar.sweep.tile import allocate_outputs

    link = (address, int((directory / "fingerprint").read_text()))
    for first, mu_cn in CHAINS:
        law, solver, cs = settings(mu_cn)
        omega = np.linspace(first, 1.0, CELLS)
        fixed = [np.full(CELLS, v) for v in (0.2, 0.5, 0.8, mu_cn)]
        outputs = [allocate_outputs(CELLS, output_bits(("label",)), 0) for _ in range(2)]
        start = time.perf_counter()
        run_chain(omega, *fixed, law, np.zeros(2), solver, cs, outputs[0])
        jit = time.perf_counter() - start
        work = make_chain_work(cs)
        work.revolution[:] = link
        start_chain(law)
        start = time.perf_counter()
        aot.chain(omega, *fixed, law, np.zeros(2), solver, cs, outputs[1], work)
        ahead = time.perf_counter() - start
        differ = [
            name
            for name, a, b in zip(outputs[0]._fields, *outputs, strict=True)
            if a.size and not np.array_equal(a, b, equal_nan=True)
        ]
        print(
            f"chain ω {first} → 1, μcn {mu_cn}: {int(outputs[1].revolutions.sum())} revolutions; "
            f"run_chain {jit:.3f} s (the first loads numba's cache), AOT {ahead:.3f} s; "
            f"arrays that differ: {differ or 'none'}"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dir", type=Path, help="build here (default: a temporary folder)")
    parser.add_argument("--compare-only", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.compare_only:
        compare(args.dir)
        return
    with tempfile.TemporaryDirectory() as scratch:
        directory = args.dir or Path(scratch)
        directory.mkdir(parents=True, exist_ok=True)
        build(directory)
        command = [sys.executable, __file__, "--dir", str(directory), "--compare-only"]
        subprocess.run(command, check=True)  # a fresh process: nothing of numba loaded


if __name__ == "__main__":
    main()
