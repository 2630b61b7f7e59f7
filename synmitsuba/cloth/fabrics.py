"""Fabric parameters per kind of cloth, as Newton's VBD cloth model reads them: areal density,
membrane stiffness against stretch and against change of area (shear), damping, bending
stiffness, friction against the body. The values were tuned by eye on our 1-3 cm
garment triangles at 10 substeps (softer membranes crumple like paper, see issue 34's note):
their order between fabrics is what matters (denim and leather stiffer and heavier than
twill, twill heavier and firmer than jersey), not real moduli. Bending at these values is far
weaker than real cloth's: an 8 cm strip of any of them held flat by one end hangs almost
straight down (74-78 mm under the clamp within a second; real fabrics' bending lengths are 2-5
cm), so the bending stiffness sets how small and how many the wrinkles are, not how a garment
drapes (bench/RESULTS.md, session 94)."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Fabric:
    density: float       # kg per square metre
    stretch: float       # Newton's tri_ke
    shear: float         # Newton's tri_ka
    damping: float       # Newton's tri_kd
    bend: float          # Newton's edge_ke: how much a fold costs
    bend_damping: float  # Newton's edge_kd
    friction: float      # against the body and the ground


# One entry per fabric: a garment kind (``cloth.kinds``) names one.
FABRICS: dict[str, Fabric] = {
    "jersey": Fabric(0.16, 6.0e3, 6.0e3, 1.0e-2, 5.0e-2, 1.0e-3, 0.5),   # knit t-shirt cotton: soft, clingy
    "woven": Fabric(0.12, 1.0e4, 1.0e4, 1.0e-2, 1.0e-1, 1.0e-3, 0.4),    # shirting, light skirts: crisp, light
    "knit": Fabric(0.30, 5.0e3, 5.0e3, 1.5e-2, 8.0e-2, 2.0e-3, 0.6),     # sweaters: heavy and stretchy
    "suiting": Fabric(0.30, 1.5e4, 1.5e4, 1.5e-2, 3.0e-1, 5.0e-3, 0.45),  # pressed wool, pleats: keeps a crease
    "denim": Fabric(0.40, 2.0e4, 2.0e4, 1.5e-2, 3.0e-1, 5.0e-3, 0.5),    # jeans, jackets: stiff, heavy
    # cotton or wool twill (trousers, chinos): lighter than denim and three times softer to bend, so the legs
    # crease at the knee and stack over the shoe (bench/RESULTS.md, session 94); its bending stiffness over its
    # weight still between jersey's and denim's
    "twill": Fabric(0.25, 1.5e4, 1.5e4, 1.5e-2, 1.0e-1, 2.0e-3, 0.45),
    "coating": Fabric(0.45, 2.0e4, 2.0e4, 1.5e-2, 3.0e-1, 5.0e-3, 0.5),  # coat wool (melton): heavy, firm
    "leather": Fabric(0.60, 3.0e4, 3.0e4, 2.0e-2, 6.0e-1, 1.0e-2, 0.6),  # holds its shape
}
