# The README's commands. Each fetches MuJoCo (once) and builds what it needs.
#   make demo    fly the final controller (policies/final) and the scripted baseline on the paper's
#                aerobatic reference, 100 randomized starts; table on stdout, CSV and plots in run/demo/
#   make test    run the whole test suite (what CI runs): formatting and lint checks, Rust tests, then the Python binding's
#   make python  build the Python package `flapper` (crates/flapper-py) into the virtual environment
#                .venv (made with $(PYTHON) if missing); `. .venv/bin/activate` then `import flapper`
#   make train   train the final controller from scratch: the whole curriculum (configs/curriculum.toml)
#                into runs/curriculum; run it again to continue after an interruption
#   make bench   simulator, environment, network and end-to-end training throughput
#   make report-deps  install (Debian/Ubuntu, needs root or sudo) what rendering, video and the browser check
#                use: Mesa's EGL software renderer, ffmpeg, chromium
#   make report  regenerate the paper's figures and tables from the shipped policies: run/report/index.html
#   make evaluate  fly POLICY (default: the final controller, policies/final) on every named reference, 100 randomized starts
#                each (seed 11): one table per reference on stdout, CSV and plots in run/evaluate/NAME/
.PHONY: lint demo test train bench baseline mujoco evaluate python python-bench report report-deps

POLICY ?= policies/final/policy.safetensors
REFERENCES = cruise longitudinal lateral sharp-turn loop immelmann roll-off-the-bottom aerobatic

CARGO ?= cargo
FLAPPER = $(CARGO) run --release --quiet -p flapper-cli --

mujoco:
	@./scripts/fetch-mujoco.sh

demo: mujoco
	$(FLAPPER) eval --policy policies/final/policy.safetensors --reference aerobatic --episodes 100 --seed 1 --out run/demo

# Layout and lints, as CI checks them (rustfmt.toml, [workspace.lints] in Cargo.toml).
lint:
	$(CARGO) fmt --all --check
	$(CARGO) clippy --workspace --all-targets --quiet -- -D warnings

PYTHON ?= python3
VENV = .venv

test: mujoco lint
	$(CARGO) test --workspace
	$(MAKE) python
	$(VENV)/bin/python -m pytest -q crates/flapper-py/tests

python: mujoco
	@test -x $(VENV)/bin/python || $(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip
	$(VENV)/bin/python -m pip install --quiet "./crates/flapper-py[test,sweep]"

python-bench: python
	$(VENV)/bin/python crates/flapper-py/benchmarks/steps_per_second.py

train: mujoco
	$(FLAPPER) curriculum --out runs/curriculum

evaluate: mujoco
	@for r in $(REFERENCES); do \
		$(FLAPPER) eval --policy $(POLICY) --reference $$r --episodes 100 --seed 11 --out run/evaluate/$$r --no-baseline || exit 1; \
	done

bench: mujoco
	$(FLAPPER) bench

baseline: mujoco
	$(FLAPPER) fly --controller scripted --seconds 15 --out run/baseline

# Debian's names; the renderer needs EGL with Mesa's software rasterizer (no GPU), the video ffmpeg,
# the browser check chromium. Skipped when everything is already there.
REPORT_DEBS = libegl1 libegl-mesa0 libgl1-mesa-dri ffmpeg chromium
SUDO = $(shell [ "$$(id -u)" = 0 ] || echo sudo)

report: mujoco
	@$(MAKE) --no-print-directory report-deps || echo "report: could not install $(REPORT_DEBS); the report is written without the pictures it cannot make"
	$(FLAPPER) report --out run/report

report-deps:
	@if dpkg -s $(REPORT_DEBS) >/dev/null 2>&1; then echo "report dependencies present: $(REPORT_DEBS)"; \
	else $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $(REPORT_DEBS); fi
