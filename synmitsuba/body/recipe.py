"""``SubjectRecipe``: everything that defines a layered human, as JSON. Rebuilding a recipe
gives byte-identical meshes and textures."""
from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from synmitsuba.body.accessories import BUILDERS, AccessoryParams, sample_accessories, sample_glasses_frames
from synmitsuba.body.anny_model import PHENOTYPE_CHECK, PHENOTYPES, height_for_stature, measures, shape_calibration
from synmitsuba.body.brows import BrowParams, sample_brows
from synmitsuba.body.eyes import EyeParams, sample_eyes
from synmitsuba.body.face_shape import FaceShapeCheck, sample_face_shape
from synmitsuba.body.garments import (GARMENTS, OUTFITS, GarmentParams, sample_footwear, sample_garment, sample_skirt_cut,
                                      sample_style)
from synmitsuba.body.hair import STYLES, HairParams, sample_hair
from synmitsuba.body.textures import SkinParams, sample_lab_colour, sample_skin
from synmitsuba.errors import ConfigError
from synmitsuba.schema import Choice, Flag, ListOf, Nested, Number, Params, Range, from_dict, optional, spec

RECIPE_VERSION = 1
# Layered subjects are built on anny; a layered SMPL-X subject does not exist yet (the bare
# SMPL-X body is synmitsuba.body.smplx_model.smplx_body).
MODELS = ("anny",)
TEXTURE_SIZES = (64, 128, 256, 512, 1024)
# How garments move: skinned with the body (fast), or the hanging ones (skirts, dresses)
# simulated over each clip by the cloth stage (synmitsuba.cloth).
CLOTH_MODES = ("skinned", "simulated")


@dataclass
class SubjectRecipe(Params):
    version: int = spec(RECIPE_VERSION, Choice((RECIPE_VERSION,)))
    model: str = spec("anny", Choice(MODELS))
    phenotypes: dict = spec(factory=dict, check=PHENOTYPE_CHECK, doc="anny: each in [0, 1]")
    betas: list = spec(factory=list, check=ListOf(Number()), doc="reserved for SMPL-X bodies")
    skin: SkinParams = spec(factory=SkinParams, check=Nested(SkinParams))
    garments: list = spec(factory=list, check=ListOf(Nested(GarmentParams)), doc="GarmentParams, any order")
    hair: HairParams = spec(factory=HairParams, check=Nested(HairParams))
    accessories: list = spec(factory=list, check=ListOf(Nested(AccessoryParams)))
    eyes: EyeParams = spec(factory=EyeParams, check=Nested(EyeParams), doc="iris colour and pattern (default brown)")
    brows: BrowParams = spec(factory=BrowParams, check=Nested(BrowParams), doc="eyebrows and eyelashes")
    face_shape: dict = spec(factory=dict, check=FaceShapeCheck(),
                            doc="MakeHuman face modifiers (body.face_shape): name -> -1..1; empty: anny's own face")
    texture_size: int = spec(1024, Choice(TEXTURE_SIZES), doc="garment texture side (the skin's is twice, at most "
                             "1024): 1024 keeps patterns sharp in a 512-px head crop; 256 builds faster, 60 MB less")
    cloth: str = spec("skinned", Choice(CLOTH_MODES), doc="skinned, or simulated: skirts, dresses and outer tops hang and swing, "
                      "simulated over each clip (synmitsuba.cloth)")

    def __post_init__(self):
        kinds = [g.kind for g in self.garments]
        if len(set(kinds)) != len(kinds):
            raise ConfigError("recipe.garments", kinds, "each garment kind may appear once")

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    @classmethod
    def from_dict(cls, d: dict, where: str = "recipe") -> "SubjectRecipe":
        if isinstance(d, dict) and d.get("model") == "smplx":
            raise ConfigError(f"{where}.model", "smplx", "layered subjects need the anny body (model: anny); for a bare "
                              "SMPL-X body use synmitsuba.body.smplx_model.smplx_body with your own model files")
        return from_dict(cls, d, where)

    @classmethod
    def from_json(cls, text: str) -> "SubjectRecipe":
        try:
            return cls.from_dict(json.loads(text))
        except json.JSONDecodeError as exc:
            raise ConfigError("recipe", text[:40], f"not JSON: {exc}") from None


ADULT_YEARS = (18.0, 80.0)  # drawn uniformly, mapped onto anny's age by its calibration
STATURE_M = {"male": (1.76, 0.07), "female": (1.63, 0.065)}  # adults' mean and standard deviation
# Adults' body mass index (kg/m^2): log-normal, median and log standard deviation per sex, a
# spread between NCD-RisC's world and NHANES's US adults (5-95 %: about 19.5-35); drawn within
# 2.5 standard deviations (16.6-41 for men), as wide as BEDLAM 2.0's 18-41.
BMI = {"male": (26.5, 0.17), "female": (26.0, 0.20)}


@dataclass
class SubjectConfig(Params):
    """What ``sample_subject`` may fix; everything else is sampled."""

    phenotypes: dict = spec(factory=dict, check=PHENOTYPE_CHECK, doc="partial anny phenotypes")
    outfit: list | None = spec(None, optional(ListOf(Choice(GARMENTS), 1)), doc="garment kinds")
    jacket: bool | None = spec(None, optional(Flag()))
    shoes: bool | None = spec(None, optional(Flag()))
    hair_style: str | None = spec(None, optional(Choice(tuple(STYLES))))
    accessories: list | None = spec(None, optional(ListOf(Choice(BUILDERS))))
    texture_size: int = spec(1024, Choice(TEXTURE_SIZES), doc="garment texture side (the skin's is twice, at most "
                             "1024): 1024 keeps patterns sharp in a 512-px head crop; 256 builds faster, 60 MB less")
    age_years: list = spec(factory=lambda: list(ADULT_YEARS), check=Range(0.0, 90.0, "years"),
                           doc="ages drawn from (adults by default; below 18 anny's calibration shapes children)")
    face_shape: bool = spec(True, Flag(), doc="draw a face of its own (body.face_shape); false: anny's face for the "
                            "phenotypes, as before 2026-12-04")
    cloth: str = spec("skinned", Choice(CLOTH_MODES), doc="skinned, or simulated: skirts, dresses and outer tops hang and swing, "
                      "simulated over each clip (synmitsuba.cloth)")


def anny_age(years: float) -> float:
    """anny's ``age`` phenotype for an age in years (anny's morphological-age anchors)."""
    anny_anchors, year_anchors = shape_calibration()["age"]
    return float(np.interp(years, year_anchors, anny_anchors))


def calibrated(sex: str, phenotype: str, age: float, u: float) -> float:
    """The ``u``-quantile of anny's calibrated Beta distribution of ``phenotype`` given ``age``
    (its WHO-fitted ``shape_calibration``): a draw from it when ``u`` is uniform."""
    from scipy.special import betaincinv  # what scipy.stats.beta.ppf calls, without scipy.stats's 1.5-s import
    ages, alphas, betas = shape_calibration()[sex][phenotype]
    a, b = np.interp(age, ages, alphas), np.interp(age, ages, betas)
    return float(betaincinv(a, b, u))


def weight_for_bmi(phenotypes: dict, bmi: float, stature: float, keep_muscle: bool = False) -> tuple[float, float]:
    """anny's ``weight`` (and, where that cannot reach the target and ``keep_muscle`` is false, a
    lower ``muscle``: anny's mass range is widest at low muscle) for a body mass index at this
    stature, from mass on a grid of weights (one batched pass per muscle tried). Returns
    (weight, muscle)."""
    grid = np.linspace(0.0, 1.0, 5)
    muscle = phenotypes["muscle"]
    for m in ((muscle,) if keep_muscle else (muscle, 0.5 * muscle, 0.0)):
        _, mass = measures([{**phenotypes, "muscle": m, "weight": float(w)} for w in grid])
        curve = mass / stature ** 2
        for k in range(len(grid) - 1):
            lo, hi = curve[k], curve[k + 1]
            if min(lo, hi) <= bmi <= max(lo, hi) and hi != lo:
                return float(grid[k] + (bmi - lo) / (hi - lo) * (grid[k + 1] - grid[k])), m
    return float(grid[np.argmin(np.abs(curve - bmi))]), m


def sample_phenotypes(rng: np.random.Generator, fixed: dict | None = None, years=ADULT_YEARS) -> dict:
    """anny phenotypes of a random person from population data: a man or a woman (gender near 0
    or near 1); age uniform in ``years`` (adults by default), mapped by anny's calibration;
    muscle and proportions from anny's WHO-calibrated distributions at that age; adults'
    stature from a normal distribution per sex (``STATURE_M``, within 2.5 standard deviations)
    reached by solving for ``height`` and body mass index from a log-normal per sex (``BMI``)
    reached by solving for ``weight``; under 18 years, height and weight from anny's
    calibration instead. ``fixed`` values win; a fixed ``height`` or ``weight`` is kept."""
    from scipy.special import ndtri  # the standard normal's quantile (scipy.stats.norm.ppf)
    fixed = fixed or {}
    u = rng.uniform(0, 1, len(PHENOTYPES))  # gender, age, muscle, weight, height, proportions
    female = rng.random() < 0.5
    sex = "female" if female else "male"
    pheno = {"gender": float(rng.uniform(0.8, 1.0) if female else rng.uniform(0.0, 0.2))}
    age_years = float(rng.uniform(*years))
    z = float(np.clip(rng.standard_normal(), -2.5, 2.5))
    if "age" in fixed:
        anny_anchors, year_anchors = shape_calibration()["age"]
        age_years = float(np.interp(fixed["age"], anny_anchors, year_anchors))
    pheno["age"] = anny_age(age_years)
    for k, i in (("muscle", 2), ("weight", 3), ("height", 4), ("proportions", 5)):
        pheno[k] = calibrated(sex, k, pheno["age"], float(u[i]))
    pheno.update(fixed)
    sex = "female" if pheno["gender"] >= 0.5 else "male"
    if age_years >= 18.0 and "height" not in fixed:
        stature = STATURE_M[sex][0] + STATURE_M[sex][1] * z
        pheno["height"] = height_for_stature(pheno, stature)
        if "weight" not in fixed:
            median, log_sd = BMI[sex]
            bmi = median * np.exp(log_sd * np.clip(ndtri(u[3]), -2.5, 2.5))
            pheno["weight"], pheno["muscle"] = weight_for_bmi(pheno, bmi, stature, "muscle" in fixed)
            pheno["height"] = height_for_stature(pheno, stature)  # weight moves the crown a little
    return {k: round(float(np.clip(pheno[k], 0.0, 1.0)), 4) for k in PHENOTYPES}


def outfit_weights(gender: float) -> np.ndarray:
    """Probabilities of ``OUTFITS``: equal for women; skirts and dresses rare (3 % in all) for men."""
    skirted = np.array([any(GARMENTS[k].skirted for k in o) for o in OUTFITS])
    w = np.where(skirted, 1.0 if gender >= 0.5 else 0.03 * (~skirted).sum() / skirted.sum() / 0.97, 1.0)
    return w / w.sum()


def sample_subject(rng: np.random.Generator, config: dict | SubjectConfig | None = None) -> SubjectRecipe:
    """A random layered human. ``config`` (a ``SubjectConfig`` or its dict) may fix:
    ``phenotypes`` (partial), ``outfit`` (garment kinds), ``jacket``, ``shoes``, ``hair_style``,
    ``accessories`` (kinds), ``texture_size``."""
    cfg = config if isinstance(config, SubjectConfig) else SubjectConfig.from_dict(config or {}, "config")
    pheno = sample_phenotypes(rng, cfg.phenotypes, cfg.age_years)
    outfit = list(cfg.outfit or OUTFITS[int(rng.choice(len(OUTFITS), p=outfit_weights(pheno["gender"])))])
    draw = rng.random() < 0.25  # drawn even when fixed, so fixing one choice keeps the others
    if (draw if cfg.jacket is None else cfg.jacket) and all(GARMENTS[k].takes_jacket for k in outfit) \
            and "jacket" not in outfit:
        outfit.append("jacket")
    draw = rng.random() < 0.85
    if (draw if cfg.shoes is None else cfg.shoes) and not any(GARMENTS[k].footwear for k in outfit):
        outfit.append("shoes")
    garments = [sample_garment(k, rng) for k in outfit]
    garments = [sample_skirt_cut(sample_footwear(g, outfit) if g.kind == "shoes" else g) for g in garments]
    # a drawn outfit's garments in their drawn styles; an outfit named in the config is worn as named
    garments = [sample_style(g, outfit, draw=g.kind not in (cfg.outfit or ())) for g in garments]
    anny_anchors, year_anchors = shape_calibration()["age"]
    hair = sample_hair(rng, "female" if pheno["gender"] >= 0.5 else "male",  # anny: gender 0 is male, 1 female
                       float(np.interp(pheno["age"], anny_anchors, year_anchors)))
    if cfg.hair_style is not None:
        hair.style = cfg.hair_style
    accessories = sample_accessories(rng)
    if cfg.accessories is not None:
        accessories = [AccessoryParams(k, sample_lab_colour(rng, (10, 80))) for k in cfg.accessories]
    skin = sample_skin(rng)
    eyes = sample_eyes(rng, skin.ita_deg, hair.melanin)  # drawn last: earlier draws stay as they were
    brows = sample_brows(rng, pheno["gender"] >= 0.5)
    skin.under_eye, skin.pores = round(float(rng.uniform(0.0, 0.8)), 3), round(float(rng.uniform(0.3, 1.0)), 3)
    sample_glasses_frames(rng, accessories)  # drawn last, for glasses wearers only
    # its own stream: every draw above, and the caller's next, as before
    face_shape = sample_face_shape(skin.seed) if cfg.face_shape else {}
    recipe = SubjectRecipe(phenotypes=pheno, skin=skin, garments=garments, hair=hair, accessories=accessories,
                           eyes=eyes, brows=brows, face_shape=face_shape, texture_size=cfg.texture_size,
                           cloth=cfg.cloth)
    return SubjectRecipe.from_dict(json.loads(recipe.to_json()))  # normalised exactly as it will be read back
