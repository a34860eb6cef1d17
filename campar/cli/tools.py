"""``campar warm-up`` and ``campar bench``."""


def add_warm_up(sub):
    text = "compile the numerical core into numba's cache once: a first point or map starts at once"
    p = sub.add_parser("warm-up", help=text)
    p.set_defaults(handler=run_warm_up)


def run_warm_up(args) -> int:
    from ..sweep.tile import warm_up

    print(f"campar warm-up: the kernel is compiled and cached ({warm_up():.1f} s)")
    return 0


def add_bench(sub):
    from ..bench import add_parser  # cheap: each benchmark imports its numerics when it runs

    add_parser(sub)  # `campar bench NAME …`: the registry in campar/bench/__init__.py
