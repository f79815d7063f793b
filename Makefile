# Every target installs what it needs first, so each works as the first command on a fresh clone.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install test test-cpu lint bench golden-spread reproduce _report calibrate examples clean model hc-check \
  sls-check grip-study-laws phantom-check \
  _grip_train _grip_eval grip-study materials scene-figure fuzz

# Python caches the checkout's bytecode (__pycache__/, ignored by git) even where the environment
# says not to: make test and make reproduce start hundreds of deformctl processes, and each would
# otherwise compile the package's modules from source again (about 0.1 s CPU each).
unexport PYTHONDONTWRITEBYTECODE

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	$(BIN)/deformctl warmup
	touch $(STAMP)

# The warm-up first: after an edit of a kernel source the kernels compile here once, not in each of
# the two pytest processes and again in the wheel's venv (which copies the checkout's compiled
# kernels: tests/_helpers/wheel.py); about 2 s of CPU when they are compiled already.
test: install
	$(BIN)/deformctl warmup
	$(BIN)/python -m pytest -n 2 -q

# make test under a CPU timer (bench/suite_cpu.py): the files and tests that took the most CPU
# time, then "make test: N s CPU (target ≤ 360 s)" with the wall time and the load average
test-cpu: install
	$(BIN)/python -m bench.suite_cpu

lint: install
	$(BIN)/ruff check deformctl tests bench examples
	$(BIN)/ruff format --check deformctl tests bench examples
	$(BIN)/mypy deformctl examples

# The benchmarks also need MuJoCo (the bench extra, for bench/bench_mujoco.py); make test does not.
BENCH_STAMP := $(VENV)/.installed-bench
$(BENCH_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[dev,bench]'
	touch $(BENCH_STAMP)

bench: $(BENCH_STAMP)
	$(BIN)/python -m bench

# The material laws' known-truth recovery and auto's choice over 400 seeded draws per law, with
# both confusion matrices (tests/characterize/test_materials.py and test_law_choice.py; make test
# runs 5).
materials: install
	DEFORMCTL_MATERIAL_DRAWS=400 $(BIN)/python -m pytest -q -s -p no:randomly \
	  tests/characterize/test_materials.py tests/characterize/test_law_choice.py

# Every shared silicone phantom through measure --weight-n 0.62 and characterize with no other
# option: none refused, D within 5 % of each file's own secant, none at_bound; with the AIC of
# Hunt-Crossley (n up to 6) against the exponential law (bench/check_phantoms.py, about a minute).
phantom-check: install
	$(BIN)/python -m bench.check_phantoms --aic

# Seeded hostile inputs through the CLI (tests/fuzz/hostile_cli.py): prints the clean fraction.
# CASES and SEED change the set.
CASES ?= 1000
SEED ?= 0
fuzz: install
	$(BIN)/python -m tests.fuzz.hostile_cli --cases $(CASES) --seed $(SEED)

# The golden numbers (tests/repro/test_golden.py) recomputed under every OpenBLAS kernel the installed
# numpy accepts x 1 and 2 BLAS threads, each number's spread beside its tolerance, then
# tests/repro/test_golden.py under each kernel (docs/reference/reproducibility.md). JOBS subprocesses
# side by side. TESTS="tests/train/test_train.py ..." runs other test files under each kernel instead.
TESTS ?= tests/repro/test_golden.py
golden-spread: install
	$(BIN)/python -m deformctl.repro.golden_spread --jobs $(JOBS) --tests $(TESTS)

# The paper's experiment end to end with the deformctl command: a seeded 73-object population
# (40 train / 33 test) and the four Table I objects, into $(RUN)/ (report.md + PNG plots).
# Each step is a file target below, so make runs independent steps side by side (JOBS at a
# time: the squeezes beside the searches, Table I and III beside the network); every step's
# output is the same whatever the order.
# Each simulating command runs in WORKERS processes (--workers): make already runs JOBS commands
# side by side, so one each keeps JOBS x WORKERS at the core count. Measured on 2 cores (same
# artifacts): one worker each, 54-58 s wall and 100-108 s of CPU; every core each (4 processes),
# 68-87 s and 116-127 s (the extra workers' start-up and the oversubscription).
RUN ?= reports
JOBS ?= 2
WORKERS ?= 1
DC := $(BIN)/deformctl
R := $(RUN)
reproduce: install
	rm -rf $(RUN) && mkdir -p $(RUN)
	$(MAKE) --no-print-directory -j$(JOBS) RUN=$(RUN) _report

$(R)/population.csv:
	$(DC) population -n 73 --seed 0 -o $@
$(R)/squeeze.mcap: $(R)/population.csv
	$(DC) measure sim $< --seed 0 --workers $(WORKERS) -o $@
$(R)/coefficients.parquet: $(R)/squeeze.mcap
	$(DC) characterize $< -o $@ > $(R)/coefficients.txt
$(R)/lift.parquet: $(R)/population.csv
	$(DC) lift sim $< --workers $(WORKERS) -o $@ --log $(R)/lift.mcap > $(R)/lift.txt
$(R)/index.parquet: $(R)/coefficients.parquet $(R)/lift.parquet
	$(DC) table $^ -o $@
$(R)/model.skops: $(R)/index.parquet
	$(DC) train $< -o $@ --hidden 2 --train-size 40 --seed 0 --metrics $(R)/metrics.json
$(R)/predictions.parquet: $(R)/model.skops $(R)/index.parquet
	$(DC) predict $^ -o $@
# the Table I and III runs need nothing of the population's; they are ordered (`|`) one after
# another on the second core, from the population's fit on, so that they never delay its chain
# (the longest): Table I's search, squeezes and fit, then Table III's nine searches, which run
# beside the chain's serial tail (table, train, predict). make gives a free slot to a target that
# has been waiting for one before it looks again, so a run that became ready earlier would take
# the slot the tail's next step needs (measured: the table or the training started 3-4 s late).
$(R)/paper_lift.parquet: | $(R)/coefficients.parquet
	$(DC) lift sim datasets/paper/objects.csv --workers $(WORKERS) -o $@ --log $(R)/paper_lift.mcap
$(R)/paper_squeeze.mcap: | $(R)/paper_lift.parquet
	$(DC) measure sim datasets/paper/objects.csv --seed 0 --workers $(WORKERS) -o $@
$(R)/paper_coefficients.parquet: $(R)/paper_squeeze.mcap
	$(DC) characterize $< -o $@
$(R)/table3_lift.parquet: | $(R)/paper_coefficients.parquet
	$(DC) lift sim datasets/paper/table3_cubes.csv --workers $(WORKERS) -o $@

# in the order make starts them: the population's chain (lift, measure, characterize, table,
# train, predict) first, Table I and III as slots free up
_report: $(R)/lift.parquet $(R)/coefficients.parquet $(R)/predictions.parquet \
  $(R)/table3_lift.parquet $(R)/paper_lift.parquet $(R)/paper_coefficients.parquet
	$(BIN)/python -m deformctl.repro.report $(RUN) --require-max-test-error 0.05 \
	  --require-beat-constant-ratio --require-ratio-span 1.2 1.7

# The simulator's Hunt–Crossley material at the paper preset's lattice: the squeeze against the law
# and the round trip through characterize --model hc (about a minute; the fast tests run 5^3).
hc-check: install
	$(BIN)/python -m bench.check_hunt_crossley

# The standard linear solid at the paper preset's lattice: its squeeze against the law and the
# round trip through characterize --model sls over population --grip's k2/D and τ ranges (~30 s)
sls-check: install
	$(BIN)/python -m bench.check_standard_linear_solid

# Fit the paper preset's two parameters to the paper's 13 simulated lifting forces and write them
# to the file the preset reads (about 2 minutes on 2 cores; prints ours vs paper, the worst and
# the leave-one-out worst error, the density check and the dt / lattice convergence).
calibrate: install
	$(BIN)/python -m deformctl.repro.calibrate --write datasets/calibration/paper.json --convergence

# The bundled grip model (datasets/models/grip.skops, `deformctl predict grip ...`): seeded grip
# populations (population --grip: W 0.5-80 N, D 5-60 N/cm, λ 0-15 N·s/cm, μ 0.2-1.0, only objects
# whose compression at F_w is at most a quarter of their width) of every material law, through
# the pipeline with the default lift sim preset: lift sim gives the truth L_f, measure sim +
# characterize the features D and λ and the law the row states, table, then train --laws (per
# law: MODEL_TRAIN rows train its network, MODEL_CAL calibrate its upper bound, the rest are its
# test rows). The training population (python -m deformctl.repro.grip_model population) is
# MODEL_N Kelvin–Voigt objects (population --grip, seed MODEL_SEED: the model's population before
# the law mix, so its Kelvin–Voigt network is trained as before) and MODEL_LAWS_N objects of the
# other laws (MODEL_LAWS: Hunt–Crossley, n in [1, 3]; standard linear solid, k2/D 0.25-3, τ
# 0.25-1 s; seed MODEL_LAWS_SEED). Then fresh populations of every law (MODEL_EVAL_N Kelvin–Voigt
# objects, seed MODEL_EVAL_SEED, and MODEL_EVAL_LAWS_N of the other laws, seed
# MODEL_EVAL_LAWS_SEED), the friction pairs and the paper's Table I objects go through the same
# pipeline, and deformctl.repro.grip_model prints the model's errors, baselines, bound coverage
# and margins (Kelvin–Voigt rows), the same per law with the first-lift rate, and the 13
# published points against MODEL_REFERENCE (today's model, copied first) (exit 1 when a target
# is missed). Prints the wall and CPU time of the training and of the evaluation. lift sim
# starts each search at MODEL_REFERENCE's prediction (about half the attempts; the bracket, and
# so the truth, is refined to 0.5 % as from any start). Intermediate files in $(MODEL_RUN)/.
# MODEL_SIM_ARGS is passed to lift sim and measure sim (e.g. --alpha-cm 10 for a quick check of
# the pipeline on a coarse lattice). MODEL_LAWS_N=0 trains on Kelvin–Voigt objects alone.
MODEL_RUN ?= build/grip
MODEL_N ?= 500
MODEL_LAWS ?= hc=1,sls=1
MODEL_LAWS_N ?= 1000
MODEL_TRAIN ?= 300
MODEL_CAL ?= 150
# each other law's network trains on at most this many rows (all its rows not calibrating)
MODEL_LAW_TRAIN ?= 1000
MODEL_SEED ?= 1
MODEL_LAWS_SEED ?= 11
MODEL_EVAL_N ?= 200
MODEL_EVAL_SEED ?= 2
MODEL_EVAL_LAWS_N ?= 400
MODEL_EVAL_LAWS_SEED ?= 12
MODEL_PRESET ?= paper
MODEL_SIM_ARGS ?=
# one squeeze log of 1,500 objects is about 2.1 GiB in memory (the default budget is 2 GiB)
MODEL_MEMORY_GIB ?= 6
MODEL_OUT ?= datasets/models/grip.skops
MODEL_REFERENCE ?= datasets/models/grip.skops
M := $(MODEL_RUN)
model: install
	rm -rf $(MODEL_RUN) && mkdir -p $(MODEL_RUN)/train $(MODEL_RUN)/test $(MODEL_RUN)/mu $(MODEL_RUN)/paper
	cp $(MODEL_REFERENCE) $(MODEL_RUN)/reference.skops
	# one make for both: the fresh objects' runs (they start at the reference model, not at the
	# new one) fill the core the training's serial steps (characterize, train) leave free
	/usr/bin/time -f "make model: training and evaluation took %e s wall, %U + %S s CPU" \
	  $(MAKE) --no-print-directory -j$(JOBS) MODEL_RUN=$(MODEL_RUN) _grip_train _grip_eval
	$(BIN)/python -m deformctl.repro.grip_model report $(MODEL_RUN) --model $(MODEL_OUT) \
	  --reference $(MODEL_RUN)/reference.skops

_grip_train: $(M)/train/index.parquet
	$(DC) train $< -o $(MODEL_OUT) --force --train-size $(MODEL_TRAIN) \
	  --calibration-size $(MODEL_CAL) --seed 0 --metrics $(M)/train/metrics.json \
	  --laws $(M)/train/coefficients.parquet --law-train-size $(MODEL_LAW_TRAIN) \
	  --note population=grip \
	  --note population_kv="n=$(MODEL_N) seed=$(MODEL_SEED)" \
	  --note population_laws="$(MODEL_LAWS) n=$(MODEL_LAWS_N) seed=$(MODEL_LAWS_SEED)" \
	  --note sim_preset=$(MODEL_PRESET) --note features_from="measure sim + characterize"

_grip_eval: $(M)/test/index.parquet $(M)/mu/index.parquet $(M)/paper/index.parquet

$(M)/train/population.csv:
	$(BIN)/python -m deformctl.repro.grip_model population --kv-n $(MODEL_N) --seed $(MODEL_SEED) \
	  --laws $(MODEL_LAWS) --laws-n $(MODEL_LAWS_N) --laws-seed $(MODEL_LAWS_SEED) -o $@
$(M)/test/population.csv:
	$(BIN)/python -m deformctl.repro.grip_model population --kv-n $(MODEL_EVAL_N) \
	  --seed $(MODEL_EVAL_SEED) --laws $(MODEL_LAWS) --laws-n $(MODEL_EVAL_LAWS_N) \
	  --laws-seed $(MODEL_EVAL_LAWS_SEED) -o $@
$(M)/mu/population.csv: $(M)/test/population.csv
	$(BIN)/python -m deformctl.repro.grip_model mu-catalog $< -o $@
$(M)/paper/population.csv:
	cp datasets/paper/objects.csv $@
$(M)/%/lift.parquet: $(M)/%/population.csv
	$(DC) lift sim $< --sim-preset $(MODEL_PRESET) $(MODEL_SIM_ARGS) --workers $(WORKERS) \
	  --start-model $(M)/reference.skops -o $@ > $(@D)/lift.txt
$(M)/%/squeeze.mcap: $(M)/%/population.csv
	$(DC) measure sim $< --sim-preset $(MODEL_PRESET) $(MODEL_SIM_ARGS) --seed 0 \
	  --workers $(WORKERS) --memory-budget-gib $(MODEL_MEMORY_GIB) -o $@
$(M)/%/coefficients.parquet: $(M)/%/squeeze.mcap
	$(DC) characterize $< -o $@ > $(@D)/coefficients.txt
$(M)/%/index.parquet: $(M)/%/coefficients.parquet $(M)/%/lift.parquet
	$(DC) table $^ -o $@
# keep every step's output (make would delete a pattern rule's intermediate files)
.PRECIOUS: $(M)/%/population.csv $(M)/%/lift.parquet $(M)/%/squeeze.mcap \
  $(M)/%/coefficients.parquet $(M)/%/index.parquet

# What the simulated lifting force depends on (μ, the groups ω_n and ζ, the box size): the
# evidence behind the grip model's form (docs/explanation/model.md), 2-4 minutes on 2 cores.
grip-study: install
	$(BIN)/python -m deformctl.repro.grip_study --jobs $(JOBS)

# The same study per law: Hunt–Crossley (pairs, μ, the exponent) and the standard linear solid
# (pairs, k2/D and τ), ~8 minutes on one core (docs/explanation/model.md quotes it)
grip-study-laws: install
	$(BIN)/python -m deformctl.repro.grip_study_laws --jobs $(JOBS)

# Every file in examples/, run as its docstring says, in a scratch folder ($(EX)/).
EX ?= .examples
examples: install
	rm -rf $(EX) && mkdir -p $(EX)
	cd $(EX) && ../$(BIN)/python ../examples/render_scene.py scene
	cd $(EX) && ../$(DC) measure images scene/top.png scene/side.png --marker-size-cm 5 \
	  --camera-matrix scene/camera.yaml --object-id red-box --weight-n 2.5 --friction-mu 0.6 \
	  -o scene/objects.csv
	cd $(EX) && ../$(DC) lift rig scene/objects.csv \
	  --command "../$(BIN)/python ../examples/frames_render_rig.py 3.0 2.6" --slip-from-frames \
	  --palm-marker-ids 1,2 --frame-marker-size-cm 2.4 -o scene/lift-frames.parquet
	cd $(EX) && ../$(BIN)/python ../examples/synthetic_index.py demo
	cd $(EX) && ../$(BIN)/python ../examples/doubtful_exports.py doubtful
	cd $(EX) && ../$(BIN)/python ../examples/make_sample_recordings.py recordings
	cd $(EX) && ../$(DC) measure bag recordings/gripper.mcap --wrench-topic /left/wrench \
	  --wrench-topic /right/wrench --position-topic /joint_states --joint gripper_width \
	  --position-is gap --object-id sponge --weight-n 0.6 -o recordings/sponge.mcap
	cd $(EX) && ../$(DC) measure csv doubtful/utm.csv --columns time=t,force=load,compression=pos \
	  --units compression=mm --object-id foam --weight-n 0.7 -o doubtful/utm.mcap
	cd $(EX) && ../$(DC) characterize doubtful/utm.mcap -o doubtful/utm.parquet
	cd $(EX) && ../$(DC) measure csv ../datasets/examples/phantom/*.csv --weight-n 0.62 -o phantoms/
	cd $(EX) && ../$(DC) characterize phantoms/ -o phantoms.parquet --model kv
	cd $(EX) && ../$(DC) lift rig ../datasets/paper/objects.csv \
	  --command "../$(BIN)/python ../examples/threshold_rig.py" -o lift-rig.parquet \
	  --log lift-rig.mcap
	cd $(EX) && ../$(DC) lift sim ../datasets/paper/objects.csv --objects D -o scene.parquet \
	  --log scene.mcap
	cd $(EX) && ../$(BIN)/python ../examples/draw_scene_frame.py scene.mcap scene.png --object D
	@echo "examples ran in $(EX)/"

# The figure of docs/guide/simulator.md: one frame of a lift log's /scene, drawn from the log.
scene-figure: install
	rm -rf .scene && mkdir -p .scene
	$(DC) lift sim datasets/paper/objects.csv -o .scene/lift.parquet --log .scene/lift.mcap
	$(BIN)/python examples/draw_scene_frame.py .scene/lift.mcap docs/foxglove/scene-frame.png \
	  --object D --index 0 --frame -1

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache build *.egg-info $(EX)
	find deformctl -name '*.nbi' -delete -o -name '*.nbc' -delete
