# The two commands of the README. Each fetches MuJoCo (once) and builds what it needs.
#   make demo   fly the scripted baseline for 15 s and write CSV + plots to run/demo/
#   make test   run the whole test suite
.PHONY: demo test bench mujoco

CARGO ?= cargo

mujoco:
	@./scripts/fetch-mujoco.sh

demo: mujoco
	$(CARGO) run --release --quiet -p flapper-cli -- fly --controller scripted --seconds 15 --out run/demo

test: mujoco
	$(CARGO) test --workspace

bench: mujoco
	$(CARGO) run --release --quiet -p flapper-cli -- bench
