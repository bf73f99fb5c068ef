# wendel: `make run` installs what is missing and runs the default scene; `make test` runs the tests.
# A second call with everything in place installs nothing.

SHELL := /bin/bash
PYTHON ?= python3
VENV := .venv
APT_PACKAGES := freefem++ libfreefem++-dev openmpi-bin libopenblas0-pthread g++ \
                libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri libglu1-mesa \
                libpetsc-real3.18-dev
# Test only: a single-node SLURM with accounting for the sweep tests (scripts/slurm-local.sh).
APT_TEST_PACKAGES := slurmctld slurmd slurm-client slurmdbd munge mariadb-server
SCENE ?= workflows/drilling-rz.toml   # the product's main job: a small drilling run in (r, z); elastic smoke: SCENE=workflows/smoke.toml

.PHONY: setup run test bench dealii clean
setup: build/.apt-ok $(VENV)/.ok build/plugins/MUMPS_mpi.so build/plugins/wendel_petsc.so build/plugins/wendel_tool.so \
       build/plugins/wendel_kernels.so build/plugins/wendel_io.so build/plugins/wendel_mesh.so \
       build/plugins/wendel_ul.so build/plugins/wendel_plast.so
	@# wendel's own bytecode, where PYTHONDONTWRITEBYTECODE=1 would compile it at every start (issue 20)
	@$(VENV)/bin/python -m compileall -q driver/wendel meshes > /dev/null

# Debian packages: FreeFEM, Open MPI, OpenBLAS under FreeFEM's direct solvers, Mesa for off-screen pictures.
build/.apt-ok: Makefile scripts/apt-ensure.sh
	@mkdir -p build
	scripts/apt-ensure.sh packages $(APT_PACKAGES)
	@touch $@

# Python: a venv with the package in editable mode, versions pinned by constraints.txt.
$(VENV)/.ok: pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install -q --upgrade pip
	$(VENV)/bin/pip install -q -c constraints.txt -e '.[test]'
	@touch $@

# The do-nothing MUMPS_mpi plugin that lets Debian's ffddm load (no PETSc/HPDDM here).
build/plugins/MUMPS_mpi.so: edp/MUMPS_mpi_placeholder.cpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O1 -w -I/usr/include/freefem++ $< -o $@

# wendel's PETSc plugin (lib/solver.idp, -solver petsc): Debian's PETSc 3.18 with hypre, ML and GAMG.
PETSC_DIR := /usr/lib/petscdir/petsc3.18/x86_64-linux-gnu-real
build/plugins/wendel_petsc.so: edp/plugins/wendel_petsc.cpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O2 -Wall -Wno-unused-variable -Wno-sign-compare -Wno-mismatched-new-delete -isystem /usr/include/freefem++ -isystem $(PETSC_DIR)/include \
	  -I/usr/lib/x86_64-linux-gnu/openmpi/include -DOMPI_SKIP_MPICXX $< -o $@ \
	  -L$(PETSC_DIR)/lib -Wl,-rpath,$(PETSC_DIR)/lib -lpetsc_real -lmpi

# wendel's compiled element kernels (lib/kernels.idp, numerics.assembly = "compiled"): no library beyond FreeFEM.
build/plugins/wendel_kernels.so: edp/plugins/wendel_kernels.cpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O2 -Wall -Wno-unused-variable -Wno-sign-compare -Wno-mismatched-new-delete -isystem /usr/include/freefem++ $< -o $@

# wendel's compiled per-cell kernels of the updated-Lagrangian kinematics (lib/kinematics.idp, kinematics-3d.idp).
build/plugins/wendel_ul.so: edp/plugins/wendel_ul.cpp edp/plugins/wendel_step.hpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O2 -ffp-contract=off -Wall -Wno-unused-variable -Wno-sign-compare -Wno-mismatched-new-delete -isystem /usr/include/freefem++ $< -o $@

# wendel's compiled Johnson-Cook return mapping (lib/plasticity.idp); no contraction into fused multiply-adds, so
# that it does the array code's operations bit for bit.
build/plugins/wendel_plast.so: edp/plugins/wendel_plast.cpp edp/plugins/wendel_step.hpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O2 -ffp-contract=off -Wall -Wno-unused-variable -Wno-sign-compare -Wno-mismatched-new-delete -isystem /usr/include/freefem++ $< -o $@

# wendel's 3D mesh reader (lib/mesh.idp): gmshload3's mesh with the face adjacency built by sorting.
build/plugins/wendel_mesh.so: edp/plugins/wendel_mesh.cpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O2 -Wall -Wno-unused-variable -Wno-sign-compare -Wno-mismatched-new-delete -isystem /usr/include/freefem++ $< -o $@

# wendel's tool plugin (lib/tool.idp): signed distance to a closed triangulated surface (an STL tool).
build/plugins/wendel_tool.so: edp/plugins/wendel_tool.cpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O2 -Wall -Wno-unused-variable -Wno-sign-compare -Wno-mismatched-new-delete -isystem /usr/include/freefem++ $< -o $@

# wendel's file writer (lib/common.idp, lib/io.idp): an increment's files written by a thread (issue 20).
build/plugins/wendel_io.so: edp/plugins/wendel_io.cpp build/.apt-ok
	@mkdir -p build/plugins
	g++ -shared -fPIC -O2 -Wall -Wno-unused-variable -Wno-sign-compare -Wno-mismatched-new-delete -isystem /usr/include/freefem++ $< -o $@ -pthread

run: setup
	$(VENV)/bin/wendel run $(SCENE)

# SLURM, munge and MariaDB for tests/test_sweep.py (their daemons are started by the test, not by apt).
build/.apt-test-ok: Makefile scripts/apt-ensure.sh
	@mkdir -p build
	scripts/apt-ensure.sh "test packages" --optional $(APT_TEST_PACKAGES)
	@touch $@

test: setup build/.apt-test-ok
	$(VENV)/bin/python -m pytest -q

bench: setup
	$(VENV)/bin/wendel bench

# deal.II 9.4, the peer of `wendel bench step42-dealii` and `step42-pair` (about 190 packages; nothing else needs it).
APT_PEER_PACKAGES := libdeal.ii-dev libdeal.ii-doc cmake
dealii: setup build/.apt-peer-ok
build/.apt-peer-ok: Makefile scripts/apt-ensure.sh
	@mkdir -p build
	scripts/apt-ensure.sh "peer packages (deal.II)" $(APT_PEER_PACKAGES)
	@touch $@

clean:
	rm -rf build results
