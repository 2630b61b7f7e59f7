"""Layered parametric humans: body models, garments, hair, accessories, textures."""
__all__: list[str] = []
