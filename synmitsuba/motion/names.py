"""Joint name maps onto the canonical humanoid names (``synmitsuba.motion.humanoid``).

A retarget between two skeleton families goes through these canonical names. Families are
recognised by their joint names; pass ``name_map`` to ``retarget`` for anything else.
"""
from __future__ import annotations

_SIDES = {"l": ("Left", ".L", "left_"), "r": ("Right", ".R", "right_")}

TORSO = ("pelvis", "spine1", "spine2", "chest", "neck", "head")  # canonical names of the trunk's joints

# canonical joint -> the child its bone points to (its "direction" joint)
BONE_CHILD = {"pelvis": "spine1", "spine1": "spine2", "spine2": "chest", "chest": "neck", "neck": "head",
              "head": "head_end"}
for s in "lr":
    BONE_CHILD.update({f"{s}_collar": f"{s}_shoulder", f"{s}_shoulder": f"{s}_elbow", f"{s}_elbow": f"{s}_wrist",
                       f"{s}_wrist": f"{s}_hand_end", f"{s}_hip": f"{s}_knee", f"{s}_knee": f"{s}_ankle",
                       f"{s}_ankle": f"{s}_toe", f"{s}_toe": f"{s}_toe_end"})


def _sided(table: dict) -> dict:
    out = {}
    for name, canon in table.items():
        if "{S}" in name or "{s}" in name or "{side}" in name:
            for s, (cap, dot, low) in _SIDES.items():
                out[name.format(S=cap, s=dot, side=low)] = canon.format(x=s)
        else:
            out[name] = canon
    return out


# family -> {its joint name: canonical name}
FAMILIES: dict[str, dict[str, str]] = {
    "anny": _sided({"root": "pelvis", "spine04": "spine1", "spine03": "spine2", "spine01": "chest",
                    "neck01": "neck", "head": "head", "clavicle{s}": "{x}_collar", "upperarm01{s}": "{x}_shoulder",
                    "lowerarm01{s}": "{x}_elbow", "wrist{s}": "{x}_wrist", "finger3-1{s}": "{x}_hand_end",
                    "upperleg01{s}": "{x}_hip", "lowerleg01{s}": "{x}_knee", "foot{s}": "{x}_ankle",
                    "toe3-1{s}": "{x}_toe"}),
    "cmu": _sided({"Hips": "pelvis", "LowerBack": "spine1", "Spine": "spine2", "Spine1": "chest", "Neck": "neck",
                   "Head": "head", "Head_end": "head_end", "{S}Shoulder": "{x}_collar", "{S}Arm": "{x}_shoulder",
                   "{S}ForeArm": "{x}_elbow", "{S}Hand": "{x}_wrist", "{S}UpLeg": "{x}_hip", "{S}Leg": "{x}_knee",
                   "{S}Foot": "{x}_ankle", "{S}ToeBase": "{x}_toe", "{S}ToeBase_end": "{x}_toe_end"}),
    "smplx": _sided({"pelvis": "pelvis", "spine1": "spine1", "spine2": "spine2", "spine3": "chest", "neck": "neck",
                     "head": "head", "{side}collar": "{x}_collar", "{side}shoulder": "{x}_shoulder",
                     "{side}elbow": "{x}_elbow", "{side}wrist": "{x}_wrist", "{side}hip": "{x}_hip",
                     "{side}knee": "{x}_knee", "{side}ankle": "{x}_ankle", "{side}foot": "{x}_toe",
                     "{side}middle1": "{x}_hand_end"}),
}
FAMILIES["humanoid"] = {c: c for c in list(BONE_CHILD) + ["head_end", "l_hand_end", "r_hand_end", "l_toe_end",
                                                          "r_toe_end"]}


def detect_family(names) -> tuple[str | None, int]:
    """The family sharing the most joint names with ``names`` (and how many)."""
    names = set(names)
    best = max(FAMILIES, key=lambda f: len(names & set(FAMILIES[f])))
    hits = len(names & set(FAMILIES[best]))
    return (best if hits >= 6 else None), hits


def canonical_map(names, family: str | None = None) -> dict[str, str]:
    """{joint name: canonical name} for the joints of a skeleton that have one."""
    family = family or detect_family(names)[0]
    if family is None:
        return {}
    table = FAMILIES[family]
    return {n: table[n] for n in names if n in table}


# SMPL / SMPL-X joints the canonical humanoid has no name for -> anny bones (anny's finger1 is
# the thumb; SMPL's hand joint sits at the middle finger's knuckle)
_ANNY_FINGER = {"thumb": 1, "index": 2, "middle": 3, "ring": 4, "pinky": 5}
_ANNY_EXTRA = {f"{side}_{finger}{k}": f"finger{n}-{k}.{side[0].upper()}" for side in ("left", "right")
               for finger, n in _ANNY_FINGER.items() for k in (1, 2, 3)}
_ANNY_EXTRA.update({"left_eye_smplhf": "eye.L", "right_eye_smplhf": "eye.R", "left_hand": "finger3-1.L",
                    "right_hand": "finger3-1.R"})


def finger_pairs(source_names, target_names) -> dict[str, str]:
    """{anny finger bone: SMPL-X finger joint} for a SMPL-X source (AMASS) and an anny target:
    the 30 finger joints ``retarget`` carries over besides the canonical ones."""
    src, tgt = set(source_names), set(target_names)
    return {anny: smplx for smplx, anny in _ANNY_EXTRA.items()
            if anny.startswith("finger") and not smplx.endswith("_hand") and smplx in src and anny in tgt}


# anny toes that bend with the one the canonical names map (the middle toe's first bone is the
# canonical toe): every source has one toe joint, at the ball, and a foot bends there as a whole
_ANNY_TOES = {f"toe{k}-1.{S}": f"toe3-1.{S}" for k in (1, 2, 4, 5) for S in "LR"}


def toe_followers(target_names) -> dict[str, str]:
    """{target toe bone: the target toe bone whose source joint it takes too}."""
    names = set(target_names)
    return {t: m for t, m in _ANNY_TOES.items() if t in names and m in names}


def body_model_to_anny(names) -> dict[str, str]:
    """{SMPL / SMPL-X joint name: anny bone} for every joint with a counterpart: the body through
    the canonical names (as retargeting maps them), hands and eyes through their own table."""
    inv_anny = {c: n for n, c in FAMILIES["anny"].items()}
    out = {n: inv_anny[c] for n, c in canonical_map(names, "smplx").items() if c in inv_anny}
    out.update({n: _ANNY_EXTRA[n] for n in names if n in _ANNY_EXTRA})
    return out
