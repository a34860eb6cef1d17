"""``campar gallery`` and ``campar report``: the study of the source paper."""


def add_gallery(sub):
    p = sub.add_parser("gallery", help="compute and draw the paper's whole figure set")
    from ..sweep.job import ModelSettings, field_choices

    p.add_argument("outdir", help="directory for the PNGs, their job files and index.md")
    p.add_argument(
        "--tensile",
        choices=("both", *field_choices(ModelSettings, "tensile")),
        default="both",
        help="force law(s) to draw: both (default; clamp with plain "
        "names, allow with '-allow' names), clamp or allow",
    )
    add_plane_arguments(p)
    p.set_defaults(handler=run_gallery)


def add_plane_arguments(p) -> None:
    """--size and --stores of the commands that compute the paper's planes first."""
    p.add_argument(
        "--size",
        choices=("small", "full"),
        default="small",
        help="small: 48×48 planes, under a minute (CI); full: the jobs' 400×400",
    )
    p.add_argument(
        "--stores", metavar="DIR", help="plane stores, reused (default results/paper-SIZE)"
    )


def run_gallery(args) -> int:
    from ..paper.gallery import make_gallery
    from ..sweep.runner import setup_logging

    setup_logging()  # the planes' progress lines
    make_gallery(args.outdir, args.size, args.tensile, args.stores)
    return 0


def add_report(sub):
    p = sub.add_parser(
        "report",
        help="write the reproduction report: the paper's claims "
        "against campar under both force laws, and the Liouville check",
    )
    p.add_argument("path", help="Markdown file to write (the committed one is docs/paper.md)")
    add_plane_arguments(p)
    p.set_defaults(handler=run_report)


def run_report(args) -> int:
    from ..paper.report import write_report
    from ..sweep.runner import setup_logging

    setup_logging()  # the planes' progress lines
    write_report(args.path, args.size, args.stores)
    return 0
