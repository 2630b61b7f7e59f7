"""Motion: procedural motions, BVH/AMASS import, retargeting, clips."""
__all__: list[str] = []
