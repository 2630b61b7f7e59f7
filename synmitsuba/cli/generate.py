"""``synmitsuba generate CONFIG --out DIR``: render a dataset, one task per sequence."""
from __future__ import annotations

import os
import sys

from synmitsuba.cli.args import natural_int, positive_int
from synmitsuba.generate.executors import EXECUTORS


def run(args) -> int:
    from synmitsuba.generate.config import load_generate_config
    from synmitsuba.generate.run import generate
    overrides = list(args.set or [])
    if args.sequences is not None:
        overrides.append(f"sequences={args.sequences}")
    if args.seed is not None:
        overrides.append(f"seed={args.seed}")
    cfg = load_generate_config(args.config, overrides)  # every key checked before any work
    if not args.quiet:  # the bar sits at 0 % for a minute or two at first: say why
        print(f"{cfg.sequences} sequence(s) on {args.workers} worker(s), {args.executor}: each worker's first sequence "
              "builds its subjects and compiles the render kernels, so it takes longest", file=sys.stderr)
    summary = generate(cfg, args.out, workers=args.workers, executor=args.executor, ray_address=args.ray_address,
                       max_failures=args.max_failures, progress=not args.quiet,
                       allow_config_change=args.allow_config_change)
    print(f"{args.out}: {summary.line()}")
    for i, err in sorted(summary.failed.items()):
        print(f"  sequence {i} failed: {err}")
    if summary.failed:
        print(f"  (each failure's traceback is in {os.path.join(args.out, 'run.log')})")
    return 1 if summary.failed else 0


def add_parser(sub) -> None:
    p = sub.add_parser("generate", help="render a dataset from a config (sharded, resumable)",
                       description="Render a dataset: one task per sequence, seeded from (seed, index) only, written "
                       "to DIR/seq_XXXXXX/ and listed in DIR/manifest.jsonl when complete. A rerun skips complete "
                       "sequences and redoes partial ones.")
    p.add_argument("config", help="generation config: a YAML path (configs/demo.yaml) or a shipped config by name "
                   "(tiny, demo, hps, crowds, nerf, compose)")
    p.add_argument("--out", required=True, help="dataset folder (created)")
    p.add_argument("--sequences", type=positive_int, help="sequences (default: the config's)")
    p.add_argument("--seed", type=natural_int, help="global seed (default: the config's)")
    p.add_argument("--workers", type=positive_int, default=1, help="parallel sequences; threads per worker = cores / workers")
    p.add_argument("--executor", choices=tuple(EXECUTORS), default="local", help="local process pool or Ray")
    p.add_argument("--ray-address", help="Ray cluster address (default: a local Ray)")
    p.add_argument("--max-failures", type=natural_int, default=2, help="retries of a failing sequence before it is reported")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a config value, e.g. render.spp=16 "
                   "(repeatable; default: the config as written)")
    p.add_argument("--allow-config-change", action="store_true", help="add sequences to a dataset made with other "
                   "settings (default: refused, naming what differs from DIR/config.json)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
