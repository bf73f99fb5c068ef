// wendel_petsc: solve FreeFEM's Newton system with a PETSc Krylov method and an algebraic multigrid.
//
// Registered in the FreeFEM language (load "wendel_petsc"):
//
//   long its = wendelPetscSolve(matrix K, real[int] b, real[int] x, real[int] fix, real[int] coords,
//                               long bs, string options, real[int] info);
//
// Every array belongs to the FreeFEM script; the plugin reads K, b, fix, coords and writes (resizes) x and info.
//
//   K        the Newton matrix, read only. Its coordinate triplets are sorted into CSR here.
//   b        right-hand side, read only: the rows with fix = 1 hold their prescribed values (already lifted
//            into the free rows by the caller, lib/solver.idp).
//   x        output, resized to K.n: the solution.
//   fix      size K.n (1 = fixed row) or 0: fixed rows and columns become identity rows and columns, scaled
//            by the mean diagonal of the free rows (and their b with them); the entries stay as explicit
//            zeros, so the sparsity pattern stays that of K.
//   coords   size K.n, node coordinates interleaved per node (x0 y0 [z0] x1 ...), or size 0: with bs > 1 the
//            rigid-body modes built from them are the near null space of GAMG and ML.
//   bs       block size (the space dimension for a displacement field, 1 for a scalar field).
//   options  PETSc options, "-name value" tokens (checked by the caller; lib/solver.idp adds its presets).
//            Besides PETSc's own: -wendel_pc_reuse 0|1 (default 1): keep the preconditioner of an earlier
//            matrix with the same pattern, rebuilt when the iterations it has cost beyond those of a fresh one
//            (at the convergence rate of the solve right after its setup) add up to more than
//            -wendel_pc_setup_its N (default 20: an ML setup measured as ~20 of its iterations on the
//            step-42 ball), or when a solve on it fails. Counts, not measured times: a run takes the same
//            path on a busy and on a quiet machine, and every rank decides alike.
//   info     output, resized to 6: iterations, true relative residual ||b - A x|| / ||b||, KSP converged
//            reason (> 0 converged), 1 if the preconditioner was reused, seconds in CSR + setup, seconds
//            in the Krylov solve.
//   returns  the iterations; a PETSc error or a solve that does not converge stops the script (ExecError).
//
//   wendelPetscRtol(real rtol): the relative tolerance of the following solves (an inexact Newton's forcing
//   term, set before each solve by lib/solver.idp); 0 (the start) leaves the options' -ksp_rtol in force.
//   Kept apart from the options string so that a new tolerance keeps the cached solver and preconditioner.
//
// On N MPI ranks (FreeFem++-mpi) every rank passes the same whole system; each rank builds its block of
// rows (whole nodes) of an MPIAIJ matrix, the solve runs on all ranks, and every rank gets the whole x.
//
//   wendelPetscLayout(real[int] order): rank-local assembly (the compiled kernels' wendelPart3 gives
//   `order`, the global PETSc index of every DoF, rank r's rows a contiguous block). From then on, on 2+ ranks,
//   a displacement system of that size is taken as this rank's part: K holds the sum over this rank's
//   elements only (the whole matrix is the sum of the ranks' parts; fixed rows need not be set), b the whole
//   right-hand side (the same on every rank) and fix is required. Each rank gives its entries in PETSc's
//   coordinate format (MatSetPreallocationCOO once per pattern, then MatSetValuesCOO per matrix: PETSc sums
//   the parts and moves the entries of rows owned by another rank; 14x faster than MatSetValues with
//   ADD_VALUES row by row, measured at 17k DoFs), the fixed rows and columns become identity rows scaled by
//   the mean free diagonal of the sum, as on one rank. Size 0 undoes it.
//
// State kept between calls: one cached solver (Mat, KSP, CSR pattern and the permutation from K's triplets
// to it) under the key (n, nnz, bs, checksum of the triplet indices, options string). A call with another
// key rebuilds everything; a call with the same key refills the values and reuses the KSP.
#include <petscksp.h>

#include "ff++.hpp"
#include "AFunction_ext.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <string>
#include <vector>

namespace {

struct Cache {
    // key
    long n = -1, nnz = -1, bs = 0;
    uint64_t pattern = 0;
    std::string options;
    // solver
    Mat A = nullptr;
    KSP ksp = nullptr;
    Vec b = nullptr, x = nullptr, r = nullptr, xAll = nullptr;
    VecScatter toAll = nullptr;                // the distributed solution to every rank (2+ ranks)
    std::vector<PetscInt> rowptr, col, diag;   // CSR of K; diag[i] = position of (i, i)
    std::vector<PetscInt> perm;                // triplet k of K -> CSR position
    std::vector<PetscScalar> val;              // values in CSR order
    PetscInt rstart = 0, rend = 0;             // this rank's rows (whole nodes: multiples of bs)
    PetscMPIInt size = 1;
    bool parts = false;                        // wendelPetscLayout: K is this rank's part of the sum
    std::vector<PetscInt> gcol;                // parts: global (PETSc) column of every CSR entry
    std::vector<long> owned;                   // parts: the DoFs whose (PETSc) rows are this rank's
    std::vector<PetscScalar> coo;              // parts: MatSetValuesCOO's values, the CSR entries then the
                                               // diagonal of every owned row (the fixed rows' scale, else 0)
    bool reuse = true;
    double rateAtSetup = 0;                    // digits of residual reduction per iteration after the setup
    double setupIts = 20;                      // -wendel_pc_setup_its: a setup's cost in Krylov iterations
    double extraIts = 0;                       // iterations beyond the setup's rate since then (kept one)
    bool stale = true;                         // rebuild the preconditioner at the next solve
};
Cache cache;
bool petscUp = false;
double forcedRtol = 0;                         // wendelPetscRtol: > 0 overrides -ksp_rtol
std::vector<PetscInt> layout;                  // wendelPetscLayout: PETSc index of every DoF (empty: identity)
bool layoutNew = false;                        // a new layout: rebuild the cached solver at the next solve

PetscErrorCode destroyCache()
{
    PetscFunctionBeginUser;
    PetscCall(KSPDestroy(&cache.ksp));
    PetscCall(MatDestroy(&cache.A));
    PetscCall(VecDestroy(&cache.b));
    PetscCall(VecDestroy(&cache.x));
    PetscCall(VecDestroy(&cache.r));
    PetscCall(VecDestroy(&cache.xAll));
    PetscCall(VecScatterDestroy(&cache.toAll));
    cache = Cache();
    PetscFunctionReturn(0);
}

void finalize()                                // at FreeFEM's exit: nothing left to stop, so errors are only printed
{
    if (!petscUp) return;
    if (destroyCache() || PetscFinalize()) std::fprintf(stderr, "wendel_petsc: PETSc finalization failed\n");
    petscUp = false;
}

PetscErrorCode startPetsc()
{
    PetscFunctionBeginUser;
    if (petscUp) PetscFunctionReturn(0);
    PetscCall(PetscInitializeNoArguments());
    PetscCall(PetscPopSignalHandler());
    petscUp = true;
    ff_atend(finalize);
    PetscFunctionReturn(0);
}

uint64_t checksum(const int* i, const int* j, size_t nnz)
{
    uint64_t h = 1469598103934665603ull;       // FNV-1a over the index pairs
    for (size_t k = 0; k < nnz; ++k) {
        h = (h ^ (uint64_t)(uint32_t)i[k]) * 1099511628211ull;
        h = (h ^ (uint64_t)(uint32_t)j[k]) * 1099511628211ull;
    }
    return h;
}

// Bucket sort of the triplets into CSR with sorted columns, and the permutation triplet -> position.
PetscErrorCode buildPattern(const HashMatrix<int, double>& H)
{
    PetscFunctionBeginUser;
    const long n = H.n, nnz = (long)H.nnz, f = H.fortran;
    cache.rowptr.assign(n + 1, 0);
    for (long k = 0; k < nnz; ++k) ++cache.rowptr[H.i[k] - f + 1];
    for (long i = 0; i < n; ++i) cache.rowptr[i + 1] += cache.rowptr[i];
    std::vector<PetscInt> next(cache.rowptr.begin(), cache.rowptr.end() - 1);
    std::vector<long> byRow(nnz);
    for (long k = 0; k < nnz; ++k) byRow[next[H.i[k] - f]++] = k;
    cache.col.resize(nnz);
    cache.perm.resize(nnz);
    cache.diag.assign(n, -1);
    for (long i = 0; i < n; ++i) {
        long* s = byRow.data() + cache.rowptr[i];
        long* e = byRow.data() + cache.rowptr[i + 1];
        std::sort(s, e, [&H](long a, long b) { return H.j[a] < H.j[b]; });
        for (long* p = s; p != e; ++p) {
            PetscInt pos = (PetscInt)(p - byRow.data());
            PetscInt c = H.j[*p] - f;
            PetscCheck(p == s || c != cache.col[pos - 1], PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
                       "duplicate entry (%ld, %ld) in the matrix", i, (long)c);
            cache.col[pos] = c;
            cache.perm[*p] = pos;
            if (c == i) cache.diag[i] = pos;
        }
    }
    PetscFunctionReturn(0);
}

// The values of K with fixed rows and columns turned into identity rows and columns scaled by the mean
// diagonal of the free rows (a unit diagonal next to stiffness entries of 1e3-1e11 upsets the AMG
// smoothers). One rank: written straight into the matrix; 2+ ranks: each rank sets its own rows.
PetscErrorCode fillValues(const HashMatrix<int, double>& H, const KN<double>& fix, double* scale)
{
    PetscFunctionBeginUser;
    const long n = H.n, nnz = (long)H.nnz, f = H.fortran;
    const bool masked = fix.N() == n;
    std::vector<PetscScalar>& v = cache.val;
    v.resize(nnz);
    for (long k = 0; k < nnz; ++k) {
        double a = H.aij[k];
        if (masked && (fix[H.i[k] - f] > 0.5 || fix[H.j[k] - f] > 0.5)) a = 0.;
        v[cache.perm[k]] = a;
    }
    *scale = 1.;
    if (cache.parts) {                         // the diagonal of the sum is the sum of the parts' diagonals
        double part[2] = {0., 0.}, sum[2];
        for (long i = 0; i < n; ++i) {
            if (fix[i] > 0.5) continue;
            if (cache.diag[i] >= 0) part[0] += v[cache.diag[i]];
            part[1] += 1.;                     // every rank counts all free rows: divided by size below
        }
        PetscCallMPI(MPI_Allreduce(part, sum, 2, MPI_DOUBLE, MPI_SUM, PETSC_COMM_WORLD));
        if (sum[1] > 0 && sum[0] > 0) *scale = std::fabs(sum[0]) / (sum[1] / cache.size);
        cache.coo.resize(nnz + cache.owned.size());
        std::copy(v.begin(), v.end(), cache.coo.begin());
        for (size_t k = 0; k < cache.owned.size(); ++k) cache.coo[nnz + k] = fix[cache.owned[k]] > 0.5 ? *scale : 0.;
        PetscCall(MatSetValuesCOO(cache.A, cache.coo.data(), INSERT_VALUES));     // sums the parts, assembles
        PetscFunctionReturn(0);
    }
    if (masked) {
        double sum = 0;
        long nFree = 0;
        for (long i = 0; i < n; ++i)
            if (fix[i] <= 0.5 && cache.diag[i] >= 0) {
                sum += std::fabs(v[cache.diag[i]]);
                ++nFree;
            }
        if (nFree > 0 && sum > 0) *scale = sum / nFree;
        for (long i = 0; i < n; ++i)
            if (fix[i] > 0.5) {
                PetscCheck(cache.diag[i] >= 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
                           "fixed row %ld has no diagonal entry in the matrix", i);
                v[cache.diag[i]] = *scale;
            }
    }
    if (cache.size == 1) {
        PetscScalar* a;
        PetscCall(MatSeqAIJGetArray(cache.A, &a));
        std::copy(v.begin(), v.end(), a);
        PetscCall(MatSeqAIJRestoreArray(cache.A, &a));
    }
    else
        for (PetscInt i = cache.rstart; i < cache.rend; ++i) {
            PetscInt p = cache.rowptr[i];
            PetscCall(MatSetValues(cache.A, 1, &i, cache.rowptr[i + 1] - p, cache.col.data() + p, v.data() + p,
                                   INSERT_VALUES));
        }
    PetscCall(MatAssemblyBegin(cache.A, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(cache.A, MAT_FINAL_ASSEMBLY));
    PetscFunctionReturn(0);
}

PetscErrorCode setupSolver(const KN<double>& coords, long bs)
{
    PetscFunctionBeginUser;
    const PetscInt n = (PetscInt)cache.n, nb = n / (PetscInt)bs;
    PetscMPIInt rank;
    PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &cache.size));
    PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
    MPI_Comm comm = cache.size == 1 ? PETSC_COMM_SELF : PETSC_COMM_WORLD;
    cache.rstart = (PetscInt)bs * (PetscInt)((long)nb * rank / cache.size);
    cache.rend = (PetscInt)bs * (PetscInt)((long)nb * (rank + 1) / cache.size);
    const PetscInt nloc = cache.rend - cache.rstart;
    PetscCall(MatCreate(comm, &cache.A));
    PetscCall(MatSetSizes(cache.A, nloc, nloc, n, n));
    PetscCall(MatSetType(cache.A, cache.size == 1 ? MATSEQAIJ : MATMPIAIJ));
    PetscCall(MatSetBlockSize(cache.A, (PetscInt)bs));
    std::vector<PetscScalar> zero(cache.nnz, 0.);
    std::vector<PetscInt> inverse;             // parts: the DoF of every PETSc index
    if (cache.parts) {                         // the pattern of the sum from the parts' coordinates (fillValues)
        inverse.assign(n, -1);
        for (PetscInt i = 0; i < n; ++i) {
            PetscCheck(layout[i] >= 0 && layout[i] < n && inverse[layout[i]] < 0, PETSC_COMM_SELF,
                       PETSC_ERR_ARG_WRONG, "wendelPetscLayout: not a permutation of 0..%ld", (long)n - 1);
            inverse[layout[i]] = i;
        }
        cache.gcol.resize(cache.col.size());
        for (size_t q = 0; q < cache.col.size(); ++q) cache.gcol[q] = layout[cache.col[q]];
        cache.owned.clear();
        for (PetscInt g = cache.rstart; g < cache.rend; ++g) cache.owned.push_back(inverse[g]);
        const size_t nnz = cache.col.size(), ncoo = nnz + cache.owned.size();
        std::vector<PetscInt> ci(ncoo), cj(ncoo);
        for (PetscInt i = 0; i < n; ++i)
            for (PetscInt p = cache.rowptr[i]; p < cache.rowptr[i + 1]; ++p) {
                ci[p] = layout[i];
                cj[p] = cache.gcol[p];
            }
        for (size_t k = 0; k < cache.owned.size(); ++k) ci[nnz + k] = cj[nnz + k] = layout[cache.owned[k]];
        PetscCall(MatSetPreallocationCOO(cache.A, (PetscCount)ncoo, ci.data(), cj.data()));
    }
    else if (cache.size == 1)
        PetscCall(MatSeqAIJSetPreallocationCSR(cache.A, cache.rowptr.data(), cache.col.data(), zero.data()));
    else {
        std::vector<PetscInt> ia(nloc + 1);
        for (PetscInt i = 0; i <= nloc; ++i) ia[i] = cache.rowptr[cache.rstart + i] - cache.rowptr[cache.rstart];
        PetscInt p0 = cache.rowptr[cache.rstart];
        PetscCall(MatMPIAIJSetPreallocationCSR(cache.A, ia.data(), cache.col.data() + p0, zero.data() + p0));
    }
    PetscCall(MatSetOption(cache.A, MAT_NEW_NONZERO_LOCATION_ERR, PETSC_TRUE));
    if (bs > 1 && coords.N() == n) {
        Vec c;
        MatNullSpace ns;
        PetscCall(VecCreate(comm, &c));
        PetscCall(VecSetSizes(c, nloc, n));
        PetscCall(VecSetBlockSize(c, (PetscInt)bs));
        PetscCall(VecSetType(c, VECSTANDARD));
        PetscScalar* pc;
        PetscCall(VecGetArray(c, &pc));
        for (PetscInt i = 0; i < nloc; ++i) pc[i] = coords[cache.parts ? inverse[cache.rstart + i] : cache.rstart + i];
        PetscCall(VecRestoreArray(c, &pc));
        PetscCall(MatNullSpaceCreateRigidBody(c, &ns));
        PetscCall(MatSetNearNullSpace(cache.A, ns));
        PetscCall(MatNullSpaceDestroy(&ns));
        PetscCall(VecDestroy(&c));
    }
    PetscCall(MatCreateVecs(cache.A, &cache.x, &cache.b));
    PetscCall(VecDuplicate(cache.b, &cache.r));
    if (cache.size > 1) PetscCall(VecScatterCreateToAll(cache.x, &cache.toAll, &cache.xAll));
    PetscCall(KSPCreate(comm, &cache.ksp));
    PetscCall(KSPSetOperators(cache.ksp, cache.A, cache.A));
    PetscCall(KSPSetFromOptions(cache.ksp));
    PetscBool reuse = PETSC_TRUE, set = PETSC_FALSE;
    PetscCall(PetscOptionsGetBool(NULL, NULL, "-wendel_pc_reuse", &reuse, &set));
    cache.reuse = reuse;
    PetscReal setupIts = 20;
    PetscCall(PetscOptionsGetReal(NULL, NULL, "-wendel_pc_setup_its", &setupIts, &set));
    cache.setupIts = setupIts;
    PetscFunctionReturn(0);
}

double seconds()                               // wall time, like the phase times of lib/mechanics.idp
{
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

PetscErrorCode solve(Matrice_Creuse<double>* K, KN<double>* b, KN<double>* x, KN<double>* fix, KN<double>* coords,
                     long bs, const std::string& options, KN<double>* info)
{
    PetscFunctionBeginUser;
    double t0 = seconds();
    HashMatrix<int, double>* H = K->pHM();
    PetscCheck(H, PETSC_COMM_SELF, PETSC_ERR_ARG_NULL, "the matrix is empty");
    PetscCheck(!H->half, PETSC_COMM_SELF, PETSC_ERR_SUP, "a matrix stored as one triangle is not supported");
    const long n = H->n;
    PetscCheck(H->m == n && b->N() == n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ,
               "matrix %ld x %ld and right-hand side %ld do not match", n, (long)H->m, (long)b->N());
    PetscCheck(fix->N() == 0 || fix->N() == n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "fix has size %ld, not 0 or %ld",
               (long)fix->N(), n);
    PetscCheck(bs >= 1 && n % bs == 0, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ, "block size %ld does not divide %ld", bs, n);
    PetscCall(startPetsc());
    PetscMPIInt size;
    PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
    const bool parts = size > 1 && (long)layout.size() == n;
    PetscCheck(!parts || fix->N() == n, PETSC_COMM_SELF, PETSC_ERR_ARG_SIZ,
               "rank-local assembly (wendelPetscLayout) needs the fixed rows (fix of size %ld)", n);
    uint64_t pattern = checksum(H->i, H->j, H->nnz);
    bool same = cache.A && cache.n == n && cache.nnz == (long)H->nnz && cache.bs == bs && cache.pattern == pattern
                && cache.options == options && cache.parts == parts && !layoutNew;
    if (size > 1) {                            // the parts' patterns differ: every rank rebuilds or none
        int mineSame = same, allSame = 0;
        PetscCallMPI(MPI_Allreduce(&mineSame, &allSame, 1, MPI_INT, MPI_LAND, PETSC_COMM_WORLD));
        same = allSame;
    }
    if (!same) {
        PetscCall(destroyCache());
        PetscCall(PetscOptionsClear(NULL));
        PetscCall(PetscOptionsInsertString(NULL, options.c_str()));
        cache.n = n;
        cache.nnz = (long)H->nnz;
        cache.bs = bs;
        cache.pattern = pattern;
        cache.options = options;
        cache.parts = parts;
        layoutNew = false;
        PetscCall(buildPattern(*H));
        PetscCall(setupSolver(*coords, bs));
    }
    double scale = 1.;
    PetscCall(fillValues(*H, *fix, &scale));
    PetscScalar* pb;
    PetscCall(VecGetArray(cache.b, &pb));
    if (cache.parts)
        for (long i : cache.owned) pb[layout[i] - cache.rstart] = (*fix)[i] > 0.5 ? scale * (*b)[i] : (*b)[i];
    else
        for (long i = cache.rstart; i < cache.rend; ++i)
            pb[i - cache.rstart] = (fix->N() == n && (*fix)[i] > 0.5) ? scale * (*b)[i] : (*b)[i];
    PetscCall(VecRestoreArray(cache.b, &pb));

    bool reused = false;
    KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
    PetscInt its = 0;
    double tSetup = 0, tSolve = 0;
    if (forcedRtol > 0) PetscCall(KSPSetTolerances(cache.ksp, forcedRtol, PETSC_DEFAULT, PETSC_DEFAULT, PETSC_DEFAULT));
    PetscReal bnorm;
    PetscCall(VecNorm(cache.b, NORM_2, &bnorm));
    for (int attempt = 0; attempt < 2; ++attempt) {
        reused = !cache.stale && cache.reuse;
        PetscCall(KSPSetReusePreconditioner(cache.ksp, reused ? PETSC_TRUE : PETSC_FALSE));
        double t1 = seconds();
        PetscCall(KSPSetUp(cache.ksp));
        PC pc;                                 // set up here, not inside KSPSolve, so that its time is its own
        PetscCall(KSPGetPC(cache.ksp, &pc));
        PetscCall(PCSetUp(pc));
        PetscCall(KSPSetUpOnBlocks(cache.ksp));
        double t2 = seconds();
        tSetup += t2 - t1;
        PetscCall(KSPSolve(cache.ksp, cache.b, cache.x));
        double t3 = seconds();
        tSolve += t3 - t2;
        PetscCall(KSPGetConvergedReason(cache.ksp, &reason));
        PetscCall(KSPGetIterationNumber(cache.ksp, &its));
        // Keep the preconditioner while the iterations it costs beyond those of a fresh one (at the rate,
        // digits of residual per iteration, of the solve right after its setup) add up to less than a setup;
        // rates rather than counts, since a forcing term changes the tolerance from solve to solve.
        PetscReal rnorm = 0;
        PetscCall(KSPGetResidualNorm(cache.ksp, &rnorm));
        double digits = (rnorm > 0 && bnorm > 0) ? std::log10(bnorm / rnorm) : 0;
        if (!reused) {
            cache.rateAtSetup = its > 0 ? digits / its : 0;
            cache.extraIts = 0;
            cache.stale = false;
            break;
        }
        if (reason > 0) {
            double fresh = cache.rateAtSetup > 0 ? digits / cache.rateAtSetup : 0;
            if (its > 0 && its > fresh) cache.extraIts += its - fresh;
            if (cache.extraIts > cache.setupIts) cache.stale = true;      // set up anew at the next solve
            break;
        }
        cache.stale = true;                                               // the kept one failed: set up and solve again
    }
    cache.stale = cache.stale || !cache.reuse;
    PetscCheck(reason > 0, PETSC_COMM_SELF, PETSC_ERR_NOT_CONVERGED,
               "the Krylov solve did not converge (KSP reason %d after %ld iterations)", (int)reason, (long)its);

    PetscReal rn, bn;
    PetscCall(MatMult(cache.A, cache.x, cache.r));
    PetscCall(VecAYPX(cache.r, -1., cache.b));
    PetscCall(VecNorm(cache.r, NORM_2, &rn));
    PetscCall(VecNorm(cache.b, NORM_2, &bn));
    x->resize(n);
    Vec xs = cache.x;
    if (cache.size > 1) {
        PetscCall(VecScatterBegin(cache.toAll, cache.x, cache.xAll, INSERT_VALUES, SCATTER_FORWARD));
        PetscCall(VecScatterEnd(cache.toAll, cache.x, cache.xAll, INSERT_VALUES, SCATTER_FORWARD));
        xs = cache.xAll;
    }
    const PetscScalar* px;
    PetscCall(VecGetArrayRead(xs, &px));
    if (cache.parts)
        for (long i = 0; i < n; ++i) (*x)[i] = px[layout[i]];
    else
        for (long i = 0; i < n; ++i) (*x)[i] = px[i];
    PetscCall(VecRestoreArrayRead(xs, &px));
    info->resize(6);
    (*info)[0] = its;
    (*info)[1] = bn > 0 ? rn / bn : rn;
    (*info)[2] = reason;
    (*info)[3] = reused ? 1 : 0;
    (*info)[4] = seconds() - t0 - tSolve;
    (*info)[5] = tSolve;
    fflush(stdout);                            // monitors and views asked for in the options: before FreeFEM exits
    PetscFunctionReturn(0);
}

long wendelPetscSolve(Matrice_Creuse<double>* const& K, KN<double>* const& b, KN<double>* const& x,
                      KN<double>* const& fix, KN<double>* const& coords, const long& bs, string* const& options,
                      KN<double>* const& info)
{
    PetscErrorCode ierr = solve(K, b, x, fix, coords, bs, *options, info);
    if (ierr) {
        const char* text = nullptr;
        if (PetscErrorMessage(ierr, &text, NULL)) text = nullptr;
        // Drop the solver: the next call starts from a clean state.
        if (destroyCache()) std::fprintf(stderr, "wendel_petsc: could not free the cached solver\n");
        ExecError((std::string("wendelPetscSolve: PETSc error ") + std::to_string((int)ierr) + " ("
                   + (text ? text : "?") + "); see the PETSc message above").c_str());
    }
    return (long)(*info)[0];
}

}  // namespace

double wendelPetscRtol(const double& rtol)
{
    forcedRtol = rtol;
    return rtol;
}

long wendelPetscLayout(KN<double>* const& order)
{
    layout.resize(order->N());
    for (long i = 0; i < order->N(); ++i) layout[i] = (PetscInt)std::lround((*order)[i]);
    layoutNew = true;
    return order->N();
}

static void Load_Init()
{
    Global.Add("wendelPetscLayout", "(", new OneOperator1_<long, KN<double>*>(wendelPetscLayout));
    Global.Add("wendelPetscRtol", "(", new OneOperator1_<double, double>(wendelPetscRtol));
    Global.Add("wendelPetscSolve", "(",
               new OneOperator8_<long, Matrice_Creuse<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*,
                                 long, string*, KN<double>*>(wendelPetscSolve));
}
LOADFUNC(Load_Init)
