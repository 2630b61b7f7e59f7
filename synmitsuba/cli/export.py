"""``synmitsuba export {coco,humandata} DIR OUT``: a generated dataset in the layouts training
code reads: COCO keypoints and masks (pycocotools), HumanData (mmhuman3d)."""
from __future__ import annotations


SUFFIX = {"coco": ".json", "humandata": ".npz"}


def run(args) -> int:
    from synmitsuba.cli.args import output_file
    from synmitsuba.io.coco import export_coco
    from synmitsuba.io.humandata import export_humandata
    from synmitsuba.io.listing import dataset_samples
    dataset_samples(args.dataset, "DATASET")  # both checked before the work
    output_file(args.out, "OUT", SUFFIX[args.format])
    if args.format == "coco":
        counts = export_coco(args.dataset, args.out, keypoint_coords=args.keypoint_coords)
    else:
        counts = export_humandata(args.dataset, args.out, data_root=args.data_root)
    print(args.out)
    print(", ".join(f"{v} {k}" for k, v in counts.items()))
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("export", help="a generated dataset as COCO (pycocotools) or HumanData (mmhuman3d)",
                       description="coco: person keypoints, masks and boxes as a COCO JSON. humandata: one npz "
                       "in mmhuman3d's HumanData layout (keypoints in its human_data convention, SMPL-X / SMPL "
                       "fits when fit-smplx wrote them). docs/FORMAT.md lists every field.")
    p.add_argument("format", choices=("coco", "humandata"), help="the layout to write")
    p.add_argument("dataset", help="a folder synmitsuba generate wrote")
    p.add_argument("out", help="the file to write (.json for coco, .npz for humandata)")
    p.add_argument("--keypoint-coords", choices=("continuous", "pixel_index"), default="continuous",
                   help="coco: pixel centres at +0.5 (continuous) or at integers (pixel_index, as detectron2 and "
                   "mmpose assume)")
    p.add_argument("--data-root", help="humandata: image_path is relative to this folder (default: DATASET; "
                   "mmhuman3d joins it onto data_prefix/datasets/NAME)")
    p.set_defaults(func=run)
