"""``synmitsuba info``: versions, the variant and the libLLVM in use."""
from __future__ import annotations

from synmitsuba.cli.args import add_variant_option


def run(args) -> int:
    import importlib.metadata as md

    import synmitsuba as sm
    from synmitsuba.engine.variant import libllvm, thread_count
    variant = sm.set_variant(args.variant)
    import drjit as dr
    rows = [("synmitsuba", sm.__version__)]
    for pkg in ("mitsuba", "drjit", "numpy", "torch", "OpenEXR", "colour-science", "trimesh", "anny"):
        try:
            rows.append((pkg, md.version(pkg)))
        except md.PackageNotFoundError:
            rows.append((pkg, "not installed"))
    rows.append(("variant", variant))
    if variant.startswith("llvm"):
        rows.append(("libLLVM", ".".join(map(str, dr.detail.llvm_version()))
                     + f" ({libllvm() or 'drjit default search'})"))
    rows.append(("threads", str(thread_count())))
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {v}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("info", help="print versions, the variant and the libLLVM in use",
                       description="Print versions, the Mitsuba variant, the libLLVM and the thread count in use.")
    add_variant_option(p, "variant to report on")
    p.set_defaults(func=run)
