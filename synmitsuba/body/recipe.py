"""``SubjectRecipe``: everything that defines a layered human, as JSON. Rebuilding a recipe
gives byte-identical meshes and textures."""
from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from synmitsuba.body.accessories import AccessoryParams, sample_accessories
from synmitsuba.body.anny_model import PHENOTYPES, check_phenotypes
from synmitsuba.body.garments import GarmentParams, sample_garment
from synmitsuba.body.hair import HairParams, sample_hair
from synmitsuba.body.textures import SkinParams, sample_skin
from synmitsuba.errors import ConfigError

RECIPE_VERSION = 1
MODELS = ("anny", "smplx")
OUTFITS = (("tshirt", "trousers"), ("tshirt", "shorts"), ("longsleeve", "trousers"), ("tshirt", "skirt"),
           ("longsleeve", "skirt"), ("dress",), ("longsleeve", "shorts"))


@dataclass
class SubjectRecipe:
    model: str = "anny"
    phenotypes: dict = field(default_factory=dict)   # anny: gender, age, muscle, weight, height, proportions
    betas: list = field(default_factory=list)        # smplx
    skin: SkinParams = field(default_factory=SkinParams)
    garments: list = field(default_factory=list)     # GarmentParams, in any order
    hair: HairParams = field(default_factory=HairParams)
    accessories: list = field(default_factory=list)  # AccessoryParams
    texture_size: int = 256
    version: int = RECIPE_VERSION

    def to_dict(self) -> dict:
        return {"version": self.version, "model": self.model, "phenotypes": dict(self.phenotypes),
                "betas": list(self.betas), "skin": self.skin.to_dict(),
                "garments": [g.to_dict() for g in self.garments], "hair": self.hair.to_dict(),
                "accessories": [a.to_dict() for a in self.accessories], "texture_size": self.texture_size}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    @classmethod
    def from_dict(cls, d: dict) -> "SubjectRecipe":
        allowed = {"version", "model", "phenotypes", "betas", "skin", "garments", "hair", "accessories", "texture_size"}
        if not isinstance(d, dict):
            raise ConfigError("recipe", type(d).__name__, "give a mapping (a recipe's to_dict())")
        for k in d:
            if k not in allowed:
                raise ConfigError(f"recipe.{k}", d[k], f"unknown field; fields: {', '.join(sorted(allowed))}")
        if d.get("version", RECIPE_VERSION) != RECIPE_VERSION:
            raise ConfigError("recipe.version", d.get("version"), f"this synmitsuba reads version {RECIPE_VERSION}")
        model = d.get("model", "anny")
        if model not in MODELS:
            raise ConfigError("recipe.model", model, f"use one of {', '.join(MODELS)}")
        size = d.get("texture_size", 256)
        if size not in (64, 128, 256, 512, 1024):
            raise ConfigError("recipe.texture_size", size, "use 64, 128, 256, 512 or 1024")
        garments = [GarmentParams.from_dict(g, f"recipe.garments[{i}]") for i, g in enumerate(d.get("garments", []))]
        kinds = [g.kind for g in garments]
        if len(set(kinds)) != len(kinds):
            raise ConfigError("recipe.garments", kinds, "each garment kind may appear once")
        return cls(model=model, phenotypes=_phenotypes(d.get("phenotypes", {})), betas=list(d.get("betas", [])),
                   skin=SkinParams.from_dict(d.get("skin", {}), "recipe.skin"), garments=garments,
                   hair=HairParams.from_dict(d.get("hair", {}), "recipe.hair"),
                   accessories=[AccessoryParams.from_dict(a, f"recipe.accessories[{i}]")
                                for i, a in enumerate(d.get("accessories", []))], texture_size=size)

    @classmethod
    def from_json(cls, text: str) -> "SubjectRecipe":
        try:
            return cls.from_dict(json.loads(text))
        except json.JSONDecodeError as exc:
            raise ConfigError("recipe", text[:40], f"not JSON: {exc}") from None


def _phenotypes(d: dict) -> dict:
    try:
        return check_phenotypes(d)
    except ConfigError as exc:
        raise ConfigError("recipe." + exc.field.split(".", 1)[1], exc.value, exc.fix) from None


def sample_subject(rng: np.random.Generator, config: dict | None = None) -> SubjectRecipe:
    """A random layered human. ``config`` may fix: ``phenotypes`` (partial), ``outfit`` (list of
    garment kinds), ``jacket`` (bool), ``shoes`` (bool), ``hair_style``, ``accessories`` (list of
    kinds), ``texture_size``."""
    config = dict(config or {})
    allowed = {"phenotypes", "outfit", "jacket", "shoes", "hair_style", "accessories", "texture_size"}
    for k in config:
        if k not in allowed:
            raise ConfigError(f"config.{k}", config[k], f"unknown key; keys: {', '.join(sorted(allowed))}")
    pheno = {k: round(float(v), 4) for k, v in zip(PHENOTYPES, rng.uniform(0, 1, len(PHENOTYPES)))}
    pheno["age"] = round(float(rng.uniform(0.45, 1.0)), 4)  # adults
    pheno.update(check_phenotypes(config.get("phenotypes", {})))
    outfit = list(config.get("outfit") or OUTFITS[int(rng.integers(len(OUTFITS)))])
    if config.get("jacket", rng.random() < 0.25) and "dress" not in outfit:
        outfit.append("jacket")
    if config.get("shoes", rng.random() < 0.85):
        outfit.append("shoes")
    garments = [sample_garment(k, rng) for k in outfit]
    for g in garments:
        g.validate(f"config.outfit[{g.kind}]")
    hair = sample_hair(rng, beard_allowed=pheno["gender"] > 0.5)
    if "hair_style" in config:
        hair.style = config["hair_style"]
        hair.validate("config")
    accessories = sample_accessories(rng)
    if "accessories" in config:
        from synmitsuba.body.accessories import AccessoryParams
        from synmitsuba.body.textures import sample_lab_colour
        accessories = [AccessoryParams(k, sample_lab_colour(rng, (10, 80))) for k in config["accessories"]]
        for a in accessories:
            a.validate("config.accessories")
    recipe = SubjectRecipe(phenotypes=pheno, skin=sample_skin(rng), garments=garments, hair=hair,
                           accessories=accessories, texture_size=config.get("texture_size", 256))
    return SubjectRecipe.from_dict(json.loads(recipe.to_json()))  # normalised exactly as it will be read back
