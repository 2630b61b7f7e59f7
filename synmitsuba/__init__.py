"""synmitsuba: synthetic, exactly annotated datasets of people rendered with Mitsuba 3.

    import synmitsuba as sm
    sm.set_variant()                     # llvm_ad_rgb on the CPU
    scene = sm.Scene(); scene.add_mesh(...)
    sample = sm.render(scene, sm.Camera.look_at(...), spp=16, seed=0)
    sm.write_sample(sample, "out/0000")
"""
__version__ = "0.1.0"

from synmitsuba.errors import ConfigError, LLVMError, SynMitsubaError
from synmitsuba.scene import *  # noqa: F401,F403
from synmitsuba.scene import __all__ as _scene_all
from synmitsuba.render import *  # noqa: F401,F403
from synmitsuba.render import __all__ as _render_all
from synmitsuba.io import *  # noqa: F401,F403
from synmitsuba.io import __all__ as _io_all
from synmitsuba.body import *  # noqa: F401,F403
from synmitsuba.body import __all__ as _body_all
from synmitsuba.motion import *  # noqa: F401,F403
from synmitsuba.motion import __all__ as _motion_all

__all__ = ["ConfigError", "LLVMError", "SynMitsubaError", *_scene_all, *_render_all, *_io_all,
           *_body_all, *_motion_all]
