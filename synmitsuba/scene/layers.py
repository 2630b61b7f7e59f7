"""Semantic layer ids written to the ``layer`` pass (uint8). 0 is background."""
from enum import IntEnum


class Layer(IntEnum):
    BACKGROUND = 0
    BODY = 1        # skin
    TOP = 2         # t-shirt, tank, long sleeve, shirt, hoodie, sweater, jacket, blazer, coat
    BOTTOM = 3      # shorts, trousers, jeans, chinos, joggers, skirt
    DRESS = 4
    SHOES = 5
    HAIR = 6
    BEARD = 7
    ACCESSORY = 8
    OBJECT = 9      # props and scene objects
    GROUND = 10
    EYES = 11       # eyeballs (sclera, iris, pupil, cornea)
    TEETH = 12      # teeth and gums
