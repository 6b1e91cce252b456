# r1: two commands. `make run` and `make test` install what is missing, build, and run.
# Build trees: build/ (RelWithDebInfo at -O2 -g1, g++), build-san/ (clang-14 at -O1: ASan + UBSan for the
# tests and the libFuzzer targets in one tree). ccache serves both when installed (R1_CCACHE).
# `make test` prints the wall time of each phase (scripts/phase.sh) and a summary at the end.
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
R1 := build/cli/r1
OUT ?= out

.PHONY: all deps configure build run view layering test test-fast test-san test-asan san-build fuzz-build fuzz-smoke install-test clean bench golden conform

all: build

deps:
	@scripts/install-deps.sh

# -g1: line tables and function names (backtraces, perf) without the
# variables' debug info, which costs a quarter to a third of each compile (R1-TEST-045); the code is -O2's.
# The test files themselves compile at -O1 (R1_TEST_OPT): a quarter less per file, and the tests
# run no slower, their time being in the libraries they call, which keep -O2.
configure: deps
	@cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
	  -DR1_TEST_OPT=-O1 -DR1_WERROR=ON $(CMAKE_FLAGS) >/dev/null

build: configure
	@cmake --build build -j $(JOBS)

# The main job on the embedded default graph: generate the crystal graph, summarise it, compute
# its epoch (focus, spectral layout, frame, encoding, hierarchy), export it as TSV and render it
# from four orbit views and one far view.
# Builds only the r1 command, so a first run does not wait for the test suites.
run: configure
	@cmake --build build -j $(JOBS) --target r1_cli
	@mkdir -p $(OUT)
	@$(R1) gen crystal -o $(OUT)/crystal.graph
	@$(R1) info $(OUT)/crystal.graph
	@echo
	@$(R1) epoch $(OUT)/crystal.graph --overlay crystal-v5 -o $(OUT)/crystal.epoch
	@$(R1) export $(OUT)/crystal.epoch --tsv $(OUT)/crystal.tsv
	@echo "per-particle table  $(OUT)/crystal.tsv"
	@echo
	@mkdir -p $(OUT)/views
	@$(R1) render $(OUT)/crystal.epoch --orbit 4 --size 960x540 -o $(OUT)/views/crystal.png
	@$(R1) render $(OUT)/crystal.epoch --distance 12000 --size 960x540 -o $(OUT)/views/crystal-far.png
	@echo "views              $(OUT)/views/ (crystal-000..003.png: orbit; crystal-far.png: the T-infinity far field)"

# The web viewer on make run's crystal epoch (made first if missing): open the printed URL in a
# browser with WebGL2. VIEW_FLAGS passes options, e.g. VIEW_FLAGS="--port 9000".
view: configure
	@cmake --build build -j $(JOBS) --target r1_cli
	@if [ ! -f $(OUT)/crystal.epoch/manifest.json ]; then mkdir -p $(OUT) && $(R1) gen crystal -o $(OUT)/crystal.graph && \
	  $(R1) epoch $(OUT)/crystal.graph --overlay crystal-v5 -o $(OUT)/crystal.epoch; fi
	@$(R1) view $(OUT)/crystal.epoch $(VIEW_FLAGS)

# The include direction first (shared/DESIGN.md; spec/backends.md R1-BKD-015): a bad include
# fails in a second, before any build (after deps, which brings python3 to a bare machine).
layering: deps
	@/usr/bin/python3 scripts/check-layering.py

test:
	@rm -f build/phases.log
	@scripts/phase.sh deps scripts/install-deps.sh
	@scripts/phase.sh layering /usr/bin/python3 scripts/check-layering.py
	@scripts/phase.sh build $(MAKE) --no-print-directory build
	@scripts/phase.sh aarch64 /usr/bin/python3 scripts/check-aarch64.py build -j $(JOBS)
	@scripts/test-costs.sh seed build main
	@scripts/phase.sh tests env R1_REQUIRE_VULKAN=1 R1_REQUIRE_BROWSER=1 ctest --test-dir build --output-on-failure -j $(JOBS) --timeout 900
	@scripts/phase.sh san-build $(MAKE) --no-print-directory san-build
	@scripts/phase.sh san-tests $(MAKE) --no-print-directory san-tests
	@scripts/phase.sh fuzz-smoke scripts/fuzz-smoke.sh $(SAN) $(FUZZ_SECONDS) $(JOBS)
	@echo "make test: passed; phase times:" >&2
	@scripts/phase-summary.sh

test-fast: layering
	@$(MAKE) --no-print-directory build
	@scripts/test-costs.sh seed build main
	@ctest --test-dir build --output-on-failure -j $(JOBS) -LE slow --timeout 900

# One clang tree for the sanitizers and libFuzzer (R1-TEST-040): ASan + UBSan at -O1 (the tests run
# several times faster than at -O0 and the sanitizers keep every check) and -g1 (line tables:
# the sanitizers' reports keep file, line and function; 4-15% less per compile than -g), the library
# coverage-instrumented for the fuzz targets. The `slow` and `install` labels are skipped (and the
# slow label's executables not built). The
# Vulkan device is left out of this tree: Mesa's driver is not built with the sanitizers and its
# allocations would read as leaks; the main tree runs the Vulkan tests (R1_REQUIRE_VULKAN).
SAN := build-san
san-build: deps
	@cmake -S . -B $(SAN) -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" \
	  -DCMAKE_CXX_COMPILER=clang++-14 -DR1_SANITIZE=ON -DR1_FUZZ=ON -DR1_BUILD_BENCH=OFF -DR1_BUILD_SLOW_TESTS=OFF -DR1_WERROR=ON -DR1_BACKEND_VULKAN=OFF \
	  $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(SAN) -j $(JOBS)

# Left out under the sanitizers, and run in `tests` (each is long there and its code runs under the
# sanitizers in shorter tests):
# - Backend.CpuStagesAreTheReferenceBitsAboveTheParallelThreshold: a 39,304-row reference solve,
#   180 s under ASan; the cpu backend's kernels and TBB splits run in CpuPanelKernels.* and the
#   every-backend tests.
# - NeuralField.ApproximatesTheAnalyticFieldOnHeldOutPoints: an accuracy check of a full training,
#   44 s; training and inference run in the other NeuralField tests.
# - CliConform.TinfCanMeasureTheNeuralField: trains a field per P_RENDER_TINF graph and times its
#   literal march (6 s here, many times that under ASan); the CLI's training and both marches run
#   in CliRender.TrainFieldAndRenderWithIt.
# - NeuralField.AFarViewsFringeFollowsTheAnalyticField: an accuracy check of a full training,
#   41 s; training and the far field's evaluation run in the other NeuralField tests.
# - CliGolden.AnUpdateShowsWhatChanged: four golden runs of the small suite, 64 s; checking and
#   writing a golden set run in CliGolden.TheReferenceReproducesTheCommittedGoldenSet and
#   CliGoldenFiles.*.
# - NeuralField.TheLiteralMarchEvaluatesEveryPixelsSamples: a training and two far frames, 42 s;
#   the literal march runs in CliRender.TrainFieldAndRenderWithIt.
# - CliIncremental.FieldIsUpdatedLocallyWithTheUpdate: three epochs with fields, 36 s; the local
#   update and the change it starts from run in NeuralField.LocalUpdateStepsOnlyTheCellsOfItsBox.
# - EpochRun.RerunsAndThreadCountsGiveIdenticalBytes: twelve epochs, 54 s; a property of the bytes
#   (the main tree's), while every stage runs under the sanitizers in EpochRun.StagesFitTogether
#   and the every-backend tests, serial and on TBB.
# - EpochRun.Fp64PositionsAgreeWithQ32WithinTheBound: eight epochs in two domains, 48 s; the fp64
#   stages run there in SpectralSpectra.RandomGraphsAgreeWithSpectraAndAcrossDomains,
#   FocusIteration.Q32AgreesWithF64 and Registry/EveryBackend.*/fp64.
# - CliConform.EachBrokenBackendFailsTheCheckItBreaks: three whole conform runs, 55 s; the checks
#   and the sidecar run there in CliConform.TheReferencePassesAndSaysItRan and NullFailsEveryCheck.
# - SpectralSpectra.RandomGraphsAgreeWithSpectraAndAcrossDomains: an agreement check against
#   Spectra on random graphs in both domains, 43 s; both domains' solves run there in
#   Spectral.Q32AndFp64Agree, Spectral.SbmSubspaceMatchesEigenDense and the closed-form tests.
# - Spectral.RerunsAndTbbAreBitIdentical: five solves of a 40,000 star, 32 s; a property of the
#   bytes across reruns and thread counts (the main tree's), whose TBB path runs the serial path's
#   bodies on the same row blocks, and those run under the sanitizers in every spectral test.
# - Block/NeuralNetworks.TrainingIsTheSameBytesOnOneThreadAndOnAll/Clifford: two trainings, 31 s;
#   a property of the bytes (the main tree's), while the threaded training runs under the
#   sanitizers in the /None instance and the Clifford network's forward pass, gradient and file in
#   the other Block/NeuralNetworks.*/Clifford tests.
SAN_EXCLUDE := ^(Spectral\.RerunsAndTbbAreBitIdentical|Block/NeuralNetworks\.TrainingIsTheSameBytesOnOneThreadAndOnAll/Clifford.*|CliConform\.EachBrokenBackendFailsTheCheckItBreaks|SpectralSpectra\.RandomGraphsAgreeWithSpectraAndAcrossDomains|EpochRun\.RerunsAndThreadCountsGiveIdenticalBytes|EpochRun\.Fp64PositionsAgreeWithQ32WithinTheBound|Backend\.CpuStagesAreTheReferenceBitsAboveTheParallelThreshold|Block/NeuralNetworks\.ApproximatesTheAnalyticFieldOnHeldOutPoints/.*|NeuralField\.AFarViewsFringeFollowsTheAnalyticField|CliGolden\.AnUpdateShowsWhatChanged|NeuralField\.TheLiteralMarchEvaluatesEveryPixelsSamples|CliConform\.TinfCanMeasureTheNeuralField|CliIncremental\.FieldIsUpdatedLocallyWithTheUpdate)$$
san-tests:
	@scripts/test-costs.sh seed $(SAN) san
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --test-dir $(SAN) --output-on-failure -j $(JOBS) -LE "slow|install|browser" -E '$(SAN_EXCLUDE)' --timeout 1800

test-san: san-build
	@$(MAKE) --no-print-directory san-tests
test-asan: test-san
fuzz-build: san-build

# Every fuzz target runs briefly from its committed corpus (FUZZ_SECONDS each).
FUZZ_SECONDS ?= 12
fuzz-smoke: san-build
	@scripts/fuzz-smoke.sh $(SAN) $(FUZZ_SECONDS) $(JOBS)

# Rewrites the committed golden set from the reference and prints what changed against it
# (spec/conformance.md R1-CONF-042). Review the printed changes before committing golden/.
golden: configure
	@cmake --build build -j $(JOBS) --target r1_cli
	@$(R1) golden -o golden/small

# Every check of R-1.0 15 on BACKEND (default reference), written to $(OUT)/r1_conformance.toml.
BACKEND ?= reference
conform: configure
	@cmake --build build -j $(JOBS) --target r1_cli
	@mkdir -p $(OUT)
	@$(R1) conform --backend $(BACKEND) -o $(OUT)/r1_conformance.toml

bench: build
	@for b in build/bench/r1_bench_*; do $$b; done

clean:
	rm -rf build build-san build-asan build-fuzz $(OUT)

install-test: build
	@scripts/install-test.sh build
