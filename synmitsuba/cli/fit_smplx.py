"""``synmitsuba fit-smplx DIR --model-path MODELS``: SMPL-X (and SMPL) labels for a generated dataset."""
from __future__ import annotations

from synmitsuba.cli.args import positive_int


def run(args) -> int:
    from synmitsuba.annotate.smplx_fit import SMPLXOptions
    from synmitsuba.generate.body_models import add_body_model_fits
    options = SMPLXOptions.from_dict({"enabled": True, "model_path": args.model_path, "smpl": args.smpl,
                                      "gender": args.gender, "n_betas": args.betas, "threshold_mm": args.threshold_mm,
                                      "hand_pca": args.hand_pca}, "")  # the files are checked first
    rows = add_body_model_fits(args.dataset, options, progress=not args.quiet)
    flagged = sum(r["flagged"] for r in rows)
    worst = max(r["surface_mean_mm"] for r in rows)
    print(f"{args.dataset}: {len(rows)} sequences, {sum(r['samples'] for r in rows)} samples fitted; worst subject "
          f"mean surface distance {worst:.1f} mm; {flagged} frames flagged above {args.threshold_mm:g} mm")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("fit-smplx", help="add SMPL-X (and SMPL) parameters to a generated dataset",
                       description="Fit SMPL-X to every subject of a generated dataset (the SynBody paper's two steps: "
                       "shape once per subject, then pose per frame) and add smplx_world / smplx_cam to each sample's "
                       "records. The model files are licensed by MPI and never shipped: register at "
                       "smpl-x.is.tue.mpg.de (SMPL: smpl.is.tue.mpg.de) and point --model-path or SMPLX_MODEL_PATH "
                       "at the folder holding SMPLX_NEUTRAL.npz.")
    p.add_argument("dataset", help="a folder synmitsuba generate wrote")
    p.add_argument("--model-path", help="folder of SMPLX_*.npz (default: $SMPLX_MODEL_PATH)")
    p.add_argument("--smpl", action="store_true",
                   help="fit SMPL too (SMPL_*.npz/.pkl there or in $SMPL_MODEL_PATH; default: SMPL-X only)")
    p.add_argument("--gender", choices=("auto", "neutral", "male", "female"), default="auto",
                   help="model file; auto fits each one present and keeps the best")
    p.add_argument("--betas", type=positive_int, default=10, help="shape coefficients fitted")
    p.add_argument("--threshold-mm", type=float, default=10.0, help="flag frames whose mean surface distance exceeds it")
    p.add_argument("--hand-pca", type=int, default=0, metavar="K",
                   help="also write each hand as K of the model file's hand PCA components (left_hand_pca, "
                   "right_hand_pca: smplx's use_pca=True, num_pca_comps=K, flat_hand_mean=False); 0: none")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
