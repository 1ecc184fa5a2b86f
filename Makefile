# bvh_collision: the commands of docs/design.md.
#   make deps    install the Debian packages the build and tests need (idempotent)
#   make build   configure and build the package and its tests (Release) in ./build
#                (make build-node: the node and the demo's programs only, what make demo builds)
#   make test    catkin_lint + every unit and launch test; last line `N passed, N failed, N skipped`
#                SANITIZE=1: the unit tests under ASan+UBSan instead (./build-sanitize);
#                CI=true: both
#   make test-busy  the Release unit and launch tests with two busy loops at normal priority
#                beside them (a robot computer is busy); not part of make test
#   make demo    start the node on the demo robot and report what it does (RVIZ=true: with rviz)
#   make bench   build and run the benchmarks (Release); build/bench/report.md with its plots
#   make soak    the node on panda for 10 minutes under load (build/soak/soak.md); not in make test
#   make fuzz    the libFuzzer targets (clang, ./build-fuzz), FUZZ_SECONDS each (default 60);
#                what they find lands in test/fuzz/corpus, which `make test` replays
SHELL := /bin/bash
# catkin needs Debian's own python3 (with catkin_pkg) ahead of any other interpreter.
export PATH := /usr/bin:$(PATH)

BUILD ?= build
JOBS ?= 2
# Compiles one more than the cores: a compiler waiting on its files or a link leaves a core idle.
BUILD_JOBS ?= 3

DEB_PACKAGES := \
  build-essential cmake python3 python3-catkin-pkg catkin catkin-lint \
  ros-core-dev libroscpp-dev rosbash python3-roslaunch python3-rostest librostest-dev \
  python3-rosnode python3-rosservice python3-rosparam \
  libstd-msgs-dev libstd-srvs-dev libgeometry-msgs-dev libsensor-msgs-dev libshape-msgs-dev libvisualization-msgs-dev \
  libdiagnostic-msgs-dev libtf2-dev libtf2-ros-dev libtf2-msgs-dev ros-robot-state-publisher \
  liburdfdom-dev liburdfdom-headers-dev libconsole-bridge-dev libtinyxml2-dev libeigen3-dev libassimp-dev liboctomap-dev \
  libgtest-dev libgmock-dev nlohmann-json3-dev libcgal-dev libgmp-dev libmpfr-dev libfcl-dev \
  libkdl-parser-dev liborocos-kdl-dev python3-matplotlib libyaml-cpp-dev \
  libompl-dev \
  pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-venv \
  python3-rospy python3-std-msgs python3-std-srvs python3-geometry-msgs python3-sensor-msgs python3-shape-msgs \
  python3-diagnostic-msgs python3-visualization-msgs \
  rviz xvfb xauth libgl1-mesa-dri imagemagick

# Only `make fuzz` needs clang and its libFuzzer runtime.
FUZZ_PACKAGES := clang libclang-rt-14-dev

.PHONY: all deps build-node build test test-busy demo bench soak fuzz clean
all: build

deps:
	@bash scripts/install_deps.sh $(DEB_PACKAGES)

# The node, its libraries and the demo's programs: all `make demo` needs (no tests, no benchmarks).
build-node: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release
	$(MAKE) -C $(BUILD) -j$(BUILD_JOBS) all

build: build-node
	$(MAKE) -C $(BUILD) -j$(BUILD_JOBS) tests

# run_tests.sh builds (as make build does) after starting the sanitized build, so that build takes
# the CPU the Release build leaves idle.
test: deps
	@BUILD=$(BUILD) JOBS=$(JOBS) BUILD_JOBS=$(BUILD_JOBS) bash scripts/run_tests.sh

test-busy: deps build
	@BUILD=$(BUILD) JOBS=$(JOBS) bash scripts/test_busy.sh

demo: build-node
	@bash scripts/demo.sh

bench: deps build
	$(MAKE) -C $(BUILD) -j$(JOBS) benchmarks
	@rm -rf $(BUILD)/bench && mkdir -p $(BUILD)/bench
	@for b in self_collision proxy_build mesh_pair environment scene_scale stability planning; do \
	  echo "== bench_$$b"; \
	  devel/lib/bvh_collision/bench_$$b $(BUILD)/bench | tee $(BUILD)/bench/bench_$$b.md; \
	  [[ $${PIPESTATUS[0]} == 0 ]] || exit 1; \
	done
	@echo "== bench_node (the node's services)"; bash scripts/bench_node.sh $(BUILD)/bench
	@python3 scripts/bench_report.py $(BUILD)/bench

soak: deps build
	@bash scripts/soak.sh $(BUILD)/soak

fuzz: deps
	@bash scripts/install_deps.sh $(FUZZ_PACKAGES)
	@JOBS=$(JOBS) bash scripts/fuzz.sh

clean:
	rm -rf $(BUILD) build-sanitize build-sanitize.configure.log build-sanitize.build.log build-sanitize.build.status \
	  build-sanitize.pass.log build-sanitize.pass.status build-fuzz build-fuzz.configure.log devel
