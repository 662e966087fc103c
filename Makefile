# vastocean: the two commands a fresh Debian machine needs are `make run` and `make test`.
# Both install what is missing first (setup), so nothing has to be installed by hand.

CARGO      ?= cargo
# Debian packages the build needs: Embree (headers + library), libclang for bindgen,
# a C compiler for the shim, a font for the labels of plots, and GNU parallel, which runs the
# study's cases (and its test).
DEB_PKGS   := libembree-dev libclang-dev pkg-config gcc fonts-dejavu-core parallel
SUDO       := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
OUT        ?= out

# The repository builds for x86-64-v3 (.cargo/config.toml); a processor without its
# instructions gets a baseline x86-64 build (slower, the same images) instead of binaries and
# build scripts that die on an illegal instruction.
V3_FLAGS   := avx2 fma bmi1 bmi2 f16c movbe abm xsave
ifeq ($(shell uname -m),x86_64)
ifneq ($(words $(V3_FLAGS)),$(words $(sort $(filter $(V3_FLAGS),$(shell grep -m1 '^flags' /proc/cpuinfo 2>/dev/null)))))
export RUSTFLAGS ?= -C target-cpu=x86-64
endif
endif

.PHONY: setup build run test test-full bench bench-report study lint man embree4-check embree4-test debian13-test clean

# Installs only the packages that are missing; apt-get update runs only when something is.
setup:
	@missing=""; for p in $(DEB_PKGS); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "setup: installing$$missing"; \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get update -qq && \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing; \
	else echo "setup: Debian packages present ($(DEB_PKGS))"; fi

build: setup
	$(CARGO) build --release

# The default scene: camera 2 m above the sea, full 360 degrees, paper-low tessellation with
# normal mapping, the built-in clear sky (Preetham's model) with the sun 3 degrees up, wrong-side
# policy terminate. Prints where the PNG is.
run: build
	./target/release/vastocean render --out $(OUT)/default

# The suite with Embree, then again on the pure-Rust backend alone; the benches are compiled
# (they must not rot) but not run: timing is `make bench`'s job.
test: setup
	$(CARGO) test --lib --tests -- --quiet
	$(CARGO) test --benches --no-run
	$(CARGO) test --no-default-features --lib --tests -- --quiet

# Heavy cases (#[ignore]) on top of the default suite.
test-full: test
	$(CARGO) test --release -- --ignored

bench: setup
	$(CARGO) bench

# The two benchmark reports docs/performance.md and docs/accuracy.md quote, regenerated in full
# into benches/results/ (each summary.json records its own run time). Nothing else may run
# meanwhile: they time things. The committed accuracy reports were measured with the paper's
# bilinear reads, the first also under the wrong-side policy bend; a regenerated report names
# both in its summary.
bench-report: build
	./target/release/vastocean bench bvh --out benches/results/bvh
	./target/release/vastocean bench accuracy --wrong-side bend --interp bilinear --out benches/results/accuracy
	./target/release/vastocean bench accuracy --filtered --interp bilinear --out benches/results/accuracy-filtered
	./target/release/vastocean bench accuracy --exact --wrong-side bend --interp bilinear --out benches/results/accuracy-exact

# The paper's study (docs/comparison.md): plans STUDY if it has no plan
# yet (STUDY_FLAGS go to `study plan`), runs its unfinished cases with GNU parallel, one case per
# core, then summarizes. Interrupt it at will: finished cases are kept, the rest rerun. The
# flags are the committed study's, its wrong-side policy (bend) and read (bilinear) included.
STUDY       ?= out/study
STUDY_FLAGS ?= --cases 93 --seed 1 --width 1024 --spp 128 --clip-sun 100 --wrong-side bend --interp bilinear
JOBS        ?= $(shell nproc)
study: build
	@[ -f $(STUDY)/plan.toml ] || ./target/release/vastocean study plan --out $(STUDY) $(STUDY_FLAGS)
	n=$$(sed -n 's/^cases = //p' $(STUDY)/plan.toml); \
	seq 1 $$n | parallel -j $(JOBS) --halt never --joblog $(STUDY)/joblog \
	  ./target/release/vastocean study run $(STUDY) --threads 1 --case {} '>>' $(STUDY)/cases/{}/run.log '2>&1'; \
	status=$$?; ./target/release/vastocean study summarize $(STUDY); exit $$status

lint: setup
	$(CARGO) fmt --check
	$(CARGO) clippy --all-targets -- -D warnings
	$(CARGO) clippy --all-targets --no-default-features -- -D warnings

# Compiles wrapper/ against Embree 4's headers from Debian 13's libembree-dev, unpacked into
# a temporary folder with its own apt state (nothing is installed), so the Embree 4 branch of
# the shim cannot rot on a Debian 12 machine.
embree4-check:
	bash .ci/embree4-check

# Builds against a real Embree 4 (4.4 from PyPI's embreex wheel, Debian 13's headers; nothing is
# installed) into target/embree4 and runs the test suite and the cross-check on it.
embree4-test: setup
	bash .ci/embree4-test

# Man pages for vastocean and each of its commands into target/man (`man -l target/man/vastocean.1`).
man: build
	./target/release/vastocean man --out target/man

# The README's two commands (`make run`, `make test`) in a Debian 13 root made with debootstrap,
# with Debian's own Embree 4: what a user on current Debian gets. Needs root.
debian13-test:
	bash .ci/debian13-test

clean:
	$(CARGO) clean
	rm -rf $(OUT)
