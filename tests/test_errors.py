"""Bad input gets an error that names the field and the value."""
import numpy as np
import pytest

from synmitsuba.errors import ConfigError, LLVMError
from synmitsuba.engine import llvm

TRI = np.array([[0, 1, 2]])
V3 = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)


def check(exc_info, *words):
    msg = str(exc_info.value)
    for w in words:
        assert w in msg, (w, msg)


def test_empty_mesh(sm):
    with pytest.raises(ConfigError) as e:
        sm.Scene().add_mesh("m", V3, np.zeros((0, 3), int))
    check(e, "m.faces", "empty mesh")


def test_non_finite_vertices(sm):
    v = V3.copy()
    v[1, 2] = np.nan
    with pytest.raises(ConfigError) as e:
        sm.Scene().add_mesh("m", v, TRI)
    check(e, "m.vertices", "row 1", "finite")


def test_faces_out_of_range(sm):
    with pytest.raises(ConfigError) as e:
        sm.Scene().add_mesh("m", V3, np.array([[0, 1, 3]]))
    check(e, "m.faces", "[0, 3]", "3 vertices")


def test_singular_K(sm):
    with pytest.raises(ConfigError) as e:
        sm.Camera(K=np.array([[0.0, 0, 10], [0, 100, 10], [0, 0, 1]]), width=20, height=20)
    check(e, "camera.K", "must be > 0")
    with pytest.raises(ConfigError) as e:  # fx, fy > 0 but singular: the fix names the real problem
        sm.Camera(K=np.array([[100.0, 100, 10], [100, 100, 10], [0, 0, 1]]), width=20, height=20)
    check(e, "camera.K", "K[1][0] must be 0")
    with pytest.raises(ConfigError) as e:
        sm.Camera(K=np.array([[100.0, 0, 10], [0, 100, 10], [0, 1, 1]]), width=20, height=20)
    check(e, "camera.K", "last row")


def test_spp_must_be_positive(sm):
    scene = sm.Scene()
    scene.add_mesh("m", V3, TRI)
    cam = sm.Camera.look_at((0, 0, 2), (0, 0, 0), width=8, height=8)
    for bad in (0, -4, 2.5):
        with pytest.raises(ConfigError) as e:
            sm.render(scene, cam, spp=bad)
        check(e, "spp", repr(bad))


def test_auto_variant_is_the_cpu_one_without_an_nvidia_driver(sm):
    import os

    from synmitsuba.engine.variant import auto_variant
    if os.path.exists("/dev/nvidiactl"):
        pytest.skip("an NVIDIA driver is present: auto may pick cuda_ad_rgb")
    assert auto_variant() == "llvm_ad_rgb"
    assert sm.set_variant("auto") == sm.current_variant() == "llvm_ad_rgb"


def test_unknown_variant(sm):
    with pytest.raises(ConfigError) as e:
        sm.set_variant("llvm_rgb_nonexistent")
    check(e, "variant", "llvm_rgb_nonexistent", "llvm_ad_rgb")
    assert sm.current_variant() == "llvm_ad_rgb"


def test_bad_ids_and_names(sm):
    with pytest.raises(ConfigError) as e:
        sm.Scene().add_mesh("m", V3, TRI, layer=300)
    check(e, "m.layer", "300")
    scene = sm.Scene()
    scene.add_mesh("m", V3, TRI)
    with pytest.raises(ConfigError) as e:
        scene.add_mesh("m", V3, TRI)
    check(e, "unique")


def test_only_old_libllvm_is_reported_clearly(monkeypatch):
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(llvm, "find_libllvm", lambda: [((15,), "/usr/lib/libLLVM-15.so.1"),
                                                       ((14,), "/usr/lib/libLLVM-14.so.1")])
    with pytest.raises(LLVMError) as e:
        llvm.choose_libllvm()
    check(e, "LLVM 15", "libLLVM >= 16", "apt-get install -y libllvm19", "DRJIT_LIBLLVM_PATH")


def test_newest_good_libllvm_is_chosen(monkeypatch):
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(llvm, "find_libllvm", lambda: [((19, 1), "/x/libLLVM.so.19.1"), ((15,), "/x/libLLVM-15.so")])
    assert llvm.choose_libllvm() == "/x/libLLVM.so.19.1"


@pytest.mark.parametrize("name,version", [("libLLVM-19.so", (19,)), ("libLLVM.so.19.1", (19, 1)),
                                          ("libLLVM-15.so.1", (15,)), ("libLLVM.17.dylib", (17,)),
                                          ("libLLVM.so", None)])
def test_libllvm_version_from_file_name(name, version):
    assert llvm.version_from_name(name) == version


def test_probe_catches_an_aborting_llvm(monkeypatch):
    """LLVM 15 aborts inside the JIT; the probe runs in a subprocess and reports instead of dying."""
    import glob
    old = sorted(glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM-15.so*"))
    if not old:
        pytest.skip("no libLLVM 15 on this machine to demonstrate the abort with")
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", old[0])
    ok, msg = llvm.probe()
    assert not ok and "libLLVM >= 16" in msg and old[0] in msg


def test_a_scene_without_light_warns_instead_of_a_silent_black_image(sm):
    scene = sm.Scene()
    scene.add_mesh("m", V3, TRI, instance=1)
    cam = sm.Camera.look_at((0, 0, 2), (0, 0, 0), width=8, height=8)
    with pytest.warns(sm.SynMitsubaWarning, match="no environment and no light"):
        s = sm.render(scene, cam, spp=1)
    assert s.mask.any() and (s.rgb == 0).all()
    scene.set_environment(sm.Constant(1.0))
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sm.render(scene, cam, spp=1)
