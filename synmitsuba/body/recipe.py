"""``SubjectRecipe``: everything that defines a layered human, as JSON. Rebuilding a recipe
gives byte-identical meshes and textures."""
from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from synmitsuba.body.accessories import BUILDERS, AccessoryParams, sample_accessories
from synmitsuba.body.anny_model import PHENOTYPE_CHECK, PHENOTYPES, height_for_stature
from synmitsuba.body.garments import GARMENTS, OUTFITS, GarmentParams, sample_garment
from synmitsuba.body.hair import STYLES, HairParams, sample_hair
from synmitsuba.body.textures import SkinParams, sample_lab_colour, sample_skin
from synmitsuba.errors import ConfigError
from synmitsuba.schema import Choice, Flag, ListOf, Nested, Number, Params, from_dict, optional, spec

RECIPE_VERSION = 1
# Layered subjects are built on anny; a layered SMPL-X subject does not exist yet (the bare
# SMPL-X body is synmitsuba.body.smplx_model.smplx_body).
MODELS = ("anny",)
TEXTURE_SIZES = (64, 128, 256, 512, 1024)


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
    texture_size: int = spec(256, Choice(TEXTURE_SIZES))

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


@dataclass
class SubjectConfig(Params):
    """What ``sample_subject`` may fix; everything else is sampled."""

    phenotypes: dict = spec(factory=dict, check=PHENOTYPE_CHECK, doc="partial anny phenotypes")
    outfit: list | None = spec(None, optional(ListOf(Choice(GARMENTS), 1)), doc="garment kinds")
    jacket: bool | None = spec(None, optional(Flag()))
    shoes: bool | None = spec(None, optional(Flag()))
    hair_style: str | None = spec(None, optional(Choice(tuple(STYLES))))
    accessories: list | None = spec(None, optional(ListOf(Choice(BUILDERS))))
    texture_size: int = spec(256, Choice(TEXTURE_SIZES))


ADULT_AGE = (0.62, 1.0)  # anny's age: 0.333 child, 0.667 young adult, 1.0 old
STATURE_M = {"male": (1.76, 0.07), "female": (1.63, 0.065)}  # adults' mean and standard deviation


def sample_phenotypes(rng: np.random.Generator, fixed: dict | None = None) -> dict:
    """anny phenotypes of a random adult: a man or a woman (gender near 0 or near 1), stature
    from a normal distribution per sex (within 2.5 standard deviations; ``STATURE_M``) reached by
    solving for ``height``; muscle, weight and proportions uniform. ``fixed`` values win; a
    fixed ``height`` is kept as given."""
    fixed = fixed or {}
    pheno = {k: round(float(v), 4) for k, v in zip(PHENOTYPES, rng.uniform(0, 1, len(PHENOTYPES)))}
    female = rng.random() < 0.5
    pheno["gender"] = round(float(rng.uniform(0.8, 1.0) if female else rng.uniform(0.0, 0.2)), 4)
    pheno["age"] = round(float(rng.uniform(*ADULT_AGE)), 4)
    z = float(np.clip(rng.standard_normal(), -2.5, 2.5))
    pheno.update(fixed)
    if "height" not in fixed:
        mean, sd = STATURE_M["female" if pheno["gender"] >= 0.5 else "male"]
        pheno["height"] = round(height_for_stature(pheno, mean + sd * z), 4)
    return pheno


def outfit_weights(gender: float) -> np.ndarray:
    """Probabilities of ``OUTFITS``: equal for women; skirts and dresses rare (3 % in all) for men."""
    skirted = np.array([bool({"skirt", "dress"} & set(o)) for o in OUTFITS])
    w = np.where(skirted, 1.0 if gender >= 0.5 else 0.03 * (~skirted).sum() / skirted.sum() / 0.97, 1.0)
    return w / w.sum()


def sample_subject(rng: np.random.Generator, config: dict | SubjectConfig | None = None) -> SubjectRecipe:
    """A random layered human. ``config`` (a ``SubjectConfig`` or its dict) may fix:
    ``phenotypes`` (partial), ``outfit`` (garment kinds), ``jacket``, ``shoes``, ``hair_style``,
    ``accessories`` (kinds), ``texture_size``."""
    cfg = config if isinstance(config, SubjectConfig) else SubjectConfig.from_dict(config or {}, "config")
    pheno = sample_phenotypes(rng, cfg.phenotypes)
    outfit = list(cfg.outfit or OUTFITS[int(rng.choice(len(OUTFITS), p=outfit_weights(pheno["gender"])))])
    draw = rng.random() < 0.25  # drawn even when fixed, so fixing one choice keeps the others
    if (draw if cfg.jacket is None else cfg.jacket) and "dress" not in outfit and "jacket" not in outfit:
        outfit.append("jacket")
    draw = rng.random() < 0.85
    if (draw if cfg.shoes is None else cfg.shoes) and "shoes" not in outfit:
        outfit.append("shoes")
    garments = [sample_garment(k, rng) for k in outfit]
    hair = sample_hair(rng, beard_allowed=pheno["gender"] < 0.5)  # anny: gender 0 is male, 1 female
    if cfg.hair_style is not None:
        hair.style = cfg.hair_style
    accessories = sample_accessories(rng)
    if cfg.accessories is not None:
        accessories = [AccessoryParams(k, sample_lab_colour(rng, (10, 80))) for k in cfg.accessories]
    recipe = SubjectRecipe(phenotypes=pheno, skin=sample_skin(rng), garments=garments, hair=hair,
                           accessories=accessories, texture_size=cfg.texture_size)
    return SubjectRecipe.from_dict(json.loads(recipe.to_json()))  # normalised exactly as it will be read back
