"""The cloth stage's stability over many random clips (issue 34: "no NaN or exploding vertex
over 1,000 random subject x motion clips"), resumable: one JSON line per clip is appended to
``--log``, and a later run skips the clips logged, so the count grows run by run
(a clip takes about a minute on one core of this CPU; 1,000 is more than one session holds).
Only rows logged on ``--since`` (default ``SAME_CLOTH_SINCE``, a commit per garment kind) or
later code count: a clip measured on an older cloth stage is run again, and the summary is over
the counted rows.

Clip ``k`` is drawn from ``numpy.random.default_rng(k)``: subjects are sampled as
``sample_subject`` draws them (``cloth: simulated``) until one wears a garment of the set of
clips (``--set``): ``hanging`` (the default, ``bench/cloth_stability.jsonl``) a skirt, dress,
shift or wrap; ``tops`` (``bench/cloth_stability_tops.jsonl``) anything else the stage
simulates: a top with nothing worn over it (since session 90), a jacket or blazer (since
session 91), trousers or shorts (since session 92), a coat (since session 96) (the hanging set's clips are the same clips as
before them: a top worn with a skirt is tucked into it; a jacket over a skirt, simulated after it
since session 92, is not measured there),
then a procedural motion kind is drawn, retargeted to it and simulated for ``--seconds``
(after the stage's own settling). Logged per clip: what was worn and done, whether the
simulation finished (or the ``ClothError`` / other exception it raised, with the garment and
frame), every vertex finite, the largest distance of a simulated vertex from the same garment
skinned and the largest step of a vertex between frames (an exploding vertex shows in both;
the stage raises ``ClothError`` past ``ClothSettings.max_drift``, 1 m), the largest distance of
a simulated vertex from the body's nearest vertex (a hem that swings far from where the skinned
one is but stays by the legs is cloth; one that flies off is not; rows logged before this was measured lack it), the largest stretch
of a simulated cloth edge (a free particle at one end or both) past its rest length (the
garment as cut, the solver's rest shape; rows from revisions before that measured it from the
cloth as put on, the solver's rest shape then: see bench/RESULTS.md; a torn or spiked piece
shows here first: rows logged before this was measured lack it), the seconds, and the code's git revision
(``rev``: rows logged before it was recorded lack it).
Prints a JSON summary of the counted rows (clips over half a metre in either: worth a look).

    python bench/cloth_stability.py [--set hanging | tops] [--clips 1000] [--seconds 1.0] [--log FILE]
                                    [--until SECONDS]   # stop starting clips after this long
                                    [--from K]          # start at clip K (skipping clips logged)
                                    [--since REV | all] # count rows from REV's code on (default: SAME_CLOTH_SINCE)
"""
import argparse
import json
import os
import subprocess
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# Per garment kind, the first commit whose cloth stage simulates it as today's: ed120b5 made the rest shape the
# garment as cut; 4dcabac collapsed edges under 2 mm, which skirts do not have (their shortest is 8 mm: clip 641,
# logged between the two, gave the same figures on today's checkout), so dresses, shifts and wraps count from it.
# The commits since changed speed and labels, not the cloth (bench/RESULTS.md, session 85). Clips logged on older
# code run again. A commit that changes what the stage computes for a kind moves its entry to itself.
# 761af63 turned every hem in along its neighbours' direction (a few millimetres on a skirt's band) and smoothed
# dresses' bodice edges (at most 4 mm): all four count from it; the 1,000 clips before it (ed120b5 and 4dcabac on)
# are to be run again (bench/RESULTS.md, session 102).
# 82edb19 stood tops' and dresses' bodices off along averaged normals over the small of the back (a tucked top is
# what a skirt hangs over): all four count from it, and the clips before it run again (bench/RESULTS.md, session 103).
# 800371c did so wherever a shell 5 cm off would turn over (under the chest, by the armpits): all four count from it.
# 6e3b41b and 2d29e54 hung bodices straight down from the bust (``hang_columns``; sideways into the room at
# most), not down their edges, and the tops tucked into a simulated skirt (skinned, what it hangs over) so too:
# all four count from 2d29e54. cfa3288 scaled bodices' and tucked tops' rest shapes by half a skinned top's
# scaling beside the armpits: all four count from it. de5a807 gave the sleeves all of it and the torso half,
# raised towards the arm's over 4 rings: all four count from it. 5ba0b02 hung long tops (a jacket over a dress
# among them) across both legs, sewn into one tube: all four count from it. 771f82c kept a jacket's, blazer's or
# coat's flank within 1.2 times the room beside the armpit (a jacket over a skirt among them): all four count from it.
SAME_CLOTH_SINCE = {"skirt": "771f82c", "dress": "771f82c", "shift": "771f82c", "wrap": "771f82c"}
# Tops (t-shirts, tanks, long sleeves, shirts, sweaters, hoodies worn with nothing over them) are simulated as today from
# 6271691, jackets and blazers over trousers or shorts from f177db3 (54b59dd made them clips of the set, so
# clips drawn before it may be other clips), and over simulated trousers and shorts, which the set counts too, from
# 06101e1: a set of their own (``--set tops``), logged apart, counted from TOPS_SINCE (below); 800371c, tops stood off along
# averaged normals wherever a shell 5 cm off would turn over (after 82edb19, over the small of the back and held taut
# over its hollows; 9c930d6, a tank's stray patches
# under the arms gone; 761af63, tops' edges smoothed along their curve and hems turned in evenly; 427d272, tops', jackets' and
# blazers' held cloth set on what they cover without turning triangles over; dbe5f8d, tops' held cloth set
# on the body; edc111f, a coat's skirt cut twice as fine for simulation; aeaa2ff, where a top over simulated trousers is set out of the body
# after them; 2ac51ce: coats simulated, and the trousers under
# them no longer held down to a coat's hem; a4ebae0: simulated trousers', shorts' and jumpsuits' legs twice as
# fine each way; e69f74c: trousers, chinos, shorts and jumpsuits as twill; 5b3c83f: their legs as tubes,
# jumpsuits in the set); 6e3b41b and 2d29e54: tops' rest shapes hung straight down from the bust, down columns, not
# edges, and sideways into the room beside the armpits at most; cfa3288: scaled by half a skinned top's beside them;
# de5a807: by all of it on the sleeves, half over the torso, raised towards the sleeve's over 4 rings; 5ba0b02:
# long tops hung across both legs under the crotch, their halves sewn into one tube (``close_middle``); 771f82c:
# jackets', blazers' and coats' flanks within 1.2 times the room beside the armpits.
TOPS_SINCE = "771f82c"
FAR = 0.5  # metres from the skinned garment (or in one frame) worth a look; ClothSettings.max_drift (1 m) raises


def hanging(recipe) -> list[str]:
    """The skirts and dresses a recipe wears (kind/cut): what the first set of clips tests."""
    return [g.kind + (f"/{g.cut}" if g.cut else "") for g in recipe.garments if g.kind in SAME_CLOTH_SINCE]


def tops(recipe) -> list[str]:
    """The garments a recipe wears that the cloth stage simulates but the hanging set's: tops
    and jackets (nothing worn over them), trousers and shorts."""
    from synmitsuba.cloth.kinds import simulated
    return [w for w in simulated(g.kind for g in recipe.garments) if w not in SAME_CLOTH_SINCE]


@dataclass(frozen=True)
class ClipSet:
    """A set of clips: the garments a drawn subject must wear (``wears``: a recipe's, listed; none:
    draw again), where its rows are logged and from which commits they count."""

    wears: Callable
    log: str
    since: dict | str


SETS = {"hanging": ClipSet(hanging, os.path.join(HERE, "cloth_stability.jsonl"), SAME_CLOTH_SINCE),
        "tops": ClipSet(tops, os.path.join(HERE, "cloth_stability_tops.jsonl"), TOPS_SINCE)}


def draw_clip(k: int, seconds: float, wears=hanging):
    """Clip ``k``'s subject (built) and retargeted motion, and what was drawn: subjects are drawn
    until one ``wears`` a garment of the set."""
    import synmitsuba as sm
    from synmitsuba.motion.procedural import KINDS
    rng = np.random.default_rng(k)
    draws = 0
    while True:
        draws += 1
        # face shapes (2026-12-04) move only the head, which no simulated garment reaches; they are left
        # out so the clips logged before them are the same clips (with them on, a skirt and a dress came
        # out bit for bit the same and a shift by up to 7 mm apart, from 24 vertices on the back's
        # mid-line at frame 0, where the body's halves tie for closest points: bench/RESULTS.md, session 89)
        recipe = sm.sample_subject(rng, {"cloth": "simulated", "texture_size": 64, "face_shape": False})
        worn = wears(recipe)
        if worn:
            break
    kind = str(rng.choice(KINDS))
    human = sm.build_subject(recipe)
    clip = sm.retarget(sm.procedural_motion(kind, rng, seconds=seconds), human.skeleton)
    return human, clip, {"clip": k, "subjects_drawn": draws, "garments": worn, "motion": kind,
                         "frames": int(clip.n_frames)}


def run_clip(k: int, seconds: float, wears=hanging) -> dict:
    """Simulate clip ``k`` and measure it (see the module's docstring)."""
    import synmitsuba as sm
    human, clip, row = draw_clip(k, seconds, wears)
    t = time.perf_counter()
    try:
        track = sm.simulate_cloth(human, clip)
    except sm.ClothError as exc:
        return {**row, "status": "ClothError", "garment": exc.garment, "frame": exc.frame, "error": str(exc)[:300],
                "seconds": round(time.perf_counter() - t, 1)}
    except Exception as exc:  # noqa: BLE001 - logged and counted
        return {**row, "status": type(exc).__name__, "error": repr(exc)[:300], "seconds": round(time.perf_counter() - t, 1)}
    seconds_taken = time.perf_counter() - t
    from scipy.spatial import cKDTree
    measured = {name: v for name, v in track.frames.items() if name in {g.split("/")[0] for g in row["garments"]}}
    stretch = max_stretch(human, clip, track, set(measured))
    finite, drift, step, off = True, 0.0, 0.0, 0.0
    for f in range(clip.n_frames):
        posed = human.pose(*clip.frame(f), face=clip.face_at(f))
        layers = {layer.name: layer for layer in posed}
        body = cKDTree(posed[0].vertices)
        for name, v in measured.items():
            finite &= bool(np.isfinite(v[f]).all())
            if not finite:
                continue
            drift = max(drift, float(np.linalg.norm(v[f] - layers[name].vertices, axis=1).max()))
            off = max(off, float(body.query(v[f])[0].max()))
            if f:
                step = max(step, float(np.linalg.norm(v[f] - v[f - 1], axis=1).max()))
    return {**row, "status": "ok", "finite": finite, "max_drift_m": round(drift, 4), "max_step_m": round(step, 4),
            "max_off_body_m": round(off, 4), "max_stretch_m": round(stretch, 4), "seconds": round(seconds_taken, 1)}


def max_stretch(human, clip, track, names: set[str]) -> float:
    """Metres the most stretched edge of any simulated garment (of ``names``) with a free particle at an end
    (held ones follow the skinned garment) is longer than at rest (the solver's rest shape:
    the garment as cut, ``ClothPiece.rest``), over every frame."""
    from synmitsuba.cloth.simulate import simulated_garments
    out = 0.0
    for g in simulated_garments(human, sorted(names)):
        r = g.piece.rest
        f = g.piece.faces
        e = np.unique(np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1), axis=0)
        e = e[~g.piece.held[e].all(axis=1)]
        length0 = np.linalg.norm(r[e[:, 0]] - r[e[:, 1]], axis=1)
        q = track.frames[g.name][:, g.rows]
        length = np.linalg.norm(q[:, e[:, 0]] - q[:, e[:, 1]], axis=2)
        out = max(out, float((length - length0).max()))
    return out


def read_log(path: str) -> list[dict]:
    if not os.path.isfile(path):
        return []
    with open(path) as fh:
        return [json.loads(line) for line in fh if line.strip()]


def summary(rows: list[dict]) -> dict:
    ok = [r for r in rows if r["status"] == "ok"]
    far = [r for r in ok if r["max_drift_m"] > FAR or r["max_step_m"] > FAR]
    failed = [r for r in rows if r["status"] != "ok"]
    return {"bench": "cloth_stability", "clips": len(rows), "finished": len(ok), "non_finite": sum(not r["finite"] for r in ok),
            "over_half_a_metre": len(far), "raised": len(failed), "raised_examples": [
                {k: r.get(k) for k in ("clip", "garments", "motion", "status", "garment", "frame")} for r in failed[:5]],
            "max_drift_m": max((r["max_drift_m"] for r in ok), default=None),
            "max_step_m": max((r["max_step_m"] for r in ok), default=None),
            "max_off_body_m": max((r["max_off_body_m"] for r in ok if "max_off_body_m" in r), default=None),
            "clips_measured_off_body": sum("max_off_body_m" in r for r in ok),
            "max_stretch_m": max((r["max_stretch_m"] for r in ok if "max_stretch_m" in r), default=None),
            "clips_measured_stretch": sum("max_stretch_m" in r for r in ok),
            "garments": {g: sum(g in r["garments"] for r in rows) for g in sorted({g for r in rows for g in r["garments"]})},
            "motions": {m: sum(r["motion"] == m for r in rows) for m in sorted({r["motion"] for r in rows})},
            "median_seconds_per_clip": float(np.median([r["seconds"] for r in rows])) if rows else None,
            "clips_by_revision": {v: sum(r.get("rev", "before revisions were logged") == v for r in rows)
                                  for v in sorted({r.get("rev", "before revisions were logged") for r in rows})}}


def _revision() -> str:
    """The checkout's commit, ``+dirty`` when its tracked code differs from it."""
    def git(*a):
        return subprocess.run(["git", *a], cwd=HERE, capture_output=True, text=True).stdout.strip()
    dirty = git("status", "--porcelain", "--untracked-files=no", "--", "../synmitsuba")
    return git("rev-parse", "--short", "HEAD") + ("+dirty" if dirty else "")


def since_filter(since: dict[str, str] | str | None):
    """A test of a log row: logged on ``since`` (a commit, or one per garment kind) or a commit
    after it (None: every row). Rows from older code, a ``+dirty`` tree or before revisions were
    logged fail it: they measured another cloth stage, so the clip is run again and only the
    new row counts."""
    memo: dict[tuple[str, str], bool] = {}

    def after(first: str, rev: str) -> bool:
        if (first, rev) not in memo:
            memo[first, rev] = subprocess.run(["git", "merge-base", "--is-ancestor", first, rev], cwd=HERE,
                                              capture_output=True).returncode == 0
        return memo[first, rev]

    def counts(row: dict) -> bool:
        rev = row.get("rev")
        if since is None:
            return True
        if not rev or rev.endswith("+dirty"):
            return False
        kinds = {g.split("/")[0] for g in row["garments"]}
        return all(after(since if isinstance(since, str) else since[k], rev) for k in kinds)
    return counts


def counted_rows(path: str, counts) -> list[dict]:
    """The log's rows that ``counts`` keeps, the last one of each clip, by clip."""
    return sorted({r["clip"]: r for r in read_log(path) if counts(r)}.values(), key=lambda r: r["clip"])


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clips", type=int, default=1000)
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--set", default="hanging", choices=sorted(SETS),
                    help="hanging: subjects in skirts and dresses; tops: in tops with nothing over them")
    ap.add_argument("--log", default=None, help="default: the set's own log in bench/")
    ap.add_argument("--until", type=float, default=None, help="start no clip after this many seconds")
    ap.add_argument("--from", dest="first", type=int, default=0,
                    help="first clip to run; clips already in the log are skipped (two processes sharing one log "
                         "take two ranges, e.g. --from 0 and --from 500)")
    ap.add_argument("--since", default=None,
                    help="count only rows logged on this commit or later ones; clips logged on older code run again "
                         "(default: SAME_CLOTH_SINCE, per garment kind; 'all' counts every row)")
    args = ap.parse_args(argv)
    clips = SETS[args.set]
    args.log = args.log or clips.log
    counts = since_filter({"all": None, None: clips.since}.get(args.since, args.since))
    start, rev = time.perf_counter(), _revision()
    for k in range(args.first, args.clips):
        if args.until is not None and time.perf_counter() - start > args.until:
            break
        if k in {r["clip"] for r in read_log(args.log) if counts(r)}:  # re-read: another process may share the log
            continue
        row = {**run_clip(k, args.seconds, clips.wears), "rev": rev}
        with open(args.log, "a") as fh:  # one line, one write: appends from two processes do not interleave
            fh.write(json.dumps(row) + "\n")
    rows = counted_rows(args.log, counts)
    return {**summary(rows), "set": args.set, "since": args.since or clips.since, "rows_not_counted": len(read_log(args.log)) - len(rows)}


if __name__ == "__main__":
    print(json.dumps(main(), indent=1))
