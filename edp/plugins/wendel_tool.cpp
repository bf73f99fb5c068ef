// wendel_tool: signed distance of a point to a closed triangulated surface (a 3D tool given as STL).
//
// Registered in the FreeFEM language (load "wendel_tool"):
//
//   real d = wendelTriDistance(real[int] tris, real[int] y, real[int] n);
//
//   tris  34 numbers per triangle, written by the driver (wendel.scene.stl) from a validated, closed and
//         consistently oriented surface (outward normals):
//           [0..8]   the vertices a, b, c
//           [9..11]  the unit face normal
//           [12..20] the angle-weighted pseudo-normals of the edges ab, bc, ca (sum of the two face normals)
//           [21..29] the angle-weighted pseudo-normals of the vertices a, b, c
//           [30..33] a bounding sphere: centre and radius
//   y     the point (3 numbers)
//   n     output (3 numbers): the gradient of the signed distance, pointing out of the tool
//   returns the signed distance: > 0 outside the tool, < 0 inside.
//
//   long nnz = wendelFricFrame(matrix A, matrix K, long nd, int[int] dof0, real[int] fE, real[int] Pb,
//                              real[int] Hb, real[int] fr);
//       The Newton matrix of lib/friction.idp in the contact nodes' local frames, in one pass over K:
//         A = (Dfree (P Q' K Q + H) Dfree + Dfix) Q'
//       with Q the rotation to the nodes' frames, P the slip rows and H their slip term, Dfree/Dfix the
//       diagonal masks of the free rows and those of fixed value. Q, P, H differ from the identity (zero for H)
//       only in the nd x nd blocks of the contact nodes, so A = L K R + B with the blocks
//         L = Dfree P Q', R = Q Dfree Q', B = (Dfree H Dfree + Dfix) Q'
//       and the identity (zero) elsewhere. Per contact node j: dof0[j] its first DoF (DoFs dof0 .. dof0 + nd - 1),
//       fE[9 j + 3 a + k] component k of frame vector a (Q[dof0 + k, dof0 + a]), Pb and Hb its P and H blocks
//       (nd x nd, row-major at nd nd j), fr[nd j + a] 1 for a free local row a, 0 for a fixed one. A may be K.
//       Returns nnz(A); A's pattern is K's with the contact nodes' rows and columns filled to whole blocks.
//
//   long wendelFricQt(long nd, int[int] dof0, real[int] fE, real[int] x, real[int] y);
//   long wendelFricKl(matrix K, long nd, int[int] dof0, real[int] fE, real[int] Pb, real[int] Hb, real[int] x,
//                     real[int] y);
//       The vectors of the same frame change (the same blocks as wendelFricFrame), y resized to x's size
//       (y may be x): y = Q' x, and y = (P Q' K Q + H) x.
//   long wendelFricRowsPQ(matrix M, long n, long nd, int[int] dof0, real[int] fE, real[int] Pb);
//       M = P Q' (n x n: the identity with the contact nodes' blocks P_j Q_j').
//
//   long nnz = wendelFbarAdd(matrix K, matrix Y, matrix Z, real[int] sinv, real[int] fr);
//       F-bar's patch term added to the Newton matrix (lib/kinematics-fbar.idp), in one pass:
//         K = K + Dfree Y' diag(sinv) Z
//       Y and Z nv x n (vertices x DoFs), sinv nv numbers (1 / the patch volumes), fr n numbers (1 for a free
//       row, 0 for a Dirichlet one). The same sum as FreeFEM's (Y Dfree)' (Ds Z) then K + that product, without
//       the three intermediate sparse matrices. Returns nnz(K).
//
//   long nc = wendelFricResidual(real[int] tool, real[int] par, int[int] dof0, real[int] u, real[int] u0,
//                                real[int] res, real[int] state, real[int] out);
//       lib/friction.idp's pass over the contact nodes at each residual (its fricResidual, the FreeFEM
//       language's loop kept as -fric_residual 1): at node j the tool's signed distance d, normal n and
//       curvature at x = X0 + u, the slip v of the increment relative to the tool (x_o = X0 + u0 at the old
//       placement), the local frame, the normal and tangential residual, the HSW sets (inactive 0, stick 1,
//       Coulomb slip 2, slip at a fixed bound 3) and the node's residual rows written into res (those of the
//       sets in state). The same arithmetic, in the same order, as the FreeFEM-language loop.
//       tool   the tool at load factor 0 (filled once by friction.idp): [0] obstacle (1 half-plane/space,
//              2 disc/ball, 5 polygon or triangulated surface), [1] dimension, [2] contact axis, [3] contact
//              direction (+-1), [4..6] reference point c, [7] radius (obstacle 2), [8..10] unit rotation
//              axis, [11] 1 for a triangulated surface, [12] nv polygon vertices (0 without), then 13 numbers per
//              vertex k (tool.idp's arrays): straight piece A, B, outward normal (tsAx, tsAy, tsBx, tsBy, tsNx,
//              tsNy), corner arc centre and radius (tcX, tcY, tcR), the normals of its two edges (tn1x, tn1y,
//              tn2x, tn2y), then (tool[11] = 1) the triangle table of wendelTriDistance, 34 numbers per triangle
//       par    [0..3] the placement now (ox, oy, oz, theta; m, rad), [4..7] the placement at the last accepted
//              increment, [8] law (0 none, 1 Coulomb, 2 Tresca), [9] mu, [10] tau (Pa), [11] c (Pa/m), [12] c_t
//              (Pa/m), [13] the first iteration's c_t at nodes that stuck (0: none), [14] heat fraction, [15] the
//              change of a slip direction that counts as a set change
//       dof0   per contact node its first DoF (dim DoFs from there); u, u0 the displacement now and at the
//              last increment (dim per vertex)
//       res    the residual (internal - external forces, every DoF): read at the contact nodes, their rows
//              then replaced by the rows of the sets in state
//       state  9 numbers per contact node, read only: the launch coordinates (3), the last solve's set, slip
//              direction (3, global axes), current mass m (lumped area) and fixed bound
//       out    resized to 35 per contact node + 8 and written: per node [0..8] frame (vector a at 3 a),
//              [9] d, [10..12] the residual at the node, [13] its normal part, [14..15] tangential parts,
//              [16..17] the tangential tractions (/ m), [18..19] the slips, [20] curvature (1/m), [21] the new
//              set, [22] its fixed bound, [23] F / |z| of a slipping node, [24..26] its slip direction,
//              [27..29] the direction of the residual rows, [30] c_t used, [31] lambda_n, [32] -d, [33] active
//              (0/1), [34] frictional heat rate (heat fraction x -r_t.v); then active, entering, leaving, stick,
//              slip, changed (set or direction), set changes, pressing force
//       returns the number of contact nodes. The caller owns every array; nothing is kept between calls.
//
//   long nc = wendelFricMass(long dim, int[int] be, real[int] beX, int[int] jOf, real[int] u, real[int] m);
//       The current lumped masses of the contact nodes (lib/friction.idp's fricCurrentMass): m set to 0, then
//       for every boundary element (dim vertices be[dim e + a], launch coordinates beX, 3 per vertex) half its
//       current length (2D) or a third of its current area (3D) added to each of its vertices with a contact
//       node index jOf[vertex] >= 0. Returns the number of elements.
//
// The closest point on each triangle by its Voronoi regions (face, edge or vertex: Ericson, Real-Time
// Collision Detection, 2005, sec. 5.1.5); the sign from the pseudo-normal of the feature holding the nearest
// point (Baerentzen and Aanaes, IEEE TVCG 11, 2005: angle-weighted pseudo-normals give the right sign for
// closed manifolds). Brute force over the triangles, skipping those whose bounding sphere is farther than
// the best distance so far: O(triangles) per call, no state kept between calls.
#include "ff++.hpp"
#include "AFunction_ext.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace {

struct V3 {
    double x, y, z;
};
inline V3 at(const double* t, long k) { return V3{t[k], t[k + 1], t[k + 2]}; }
inline V3 operator-(V3 a, V3 b) { return V3{a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator+(V3 a, V3 b) { return V3{a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator*(double s, V3 a) { return V3{s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Closest point of p on the triangle (a, b, c) and its feature: 0 face, 1..3 edges ab, bc, ca, 4..6 vertices.
V3 closest(V3 p, V3 a, V3 b, V3 c, int& feature)
{
    V3 ab = b - a, ac = c - a, ap = p - a;
    double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) { feature = 4; return a; }
    V3 bp = p - b;
    double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) { feature = 5; return b; }
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) { feature = 1; return a + (d1 / (d1 - d3)) * ab; }
    V3 cp = p - c;
    double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) { feature = 6; return c; }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) { feature = 3; return a + (d2 / (d2 - d6)) * ac; }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        feature = 2;
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    }
    double den = 1.0 / (va + vb + vc);
    feature = 0;
    return a + (vb * den) * ab + (vc * den) * ac;
}

// The signed distance of p to the nt triangles of the table t (34 numbers each), its gradient in n.
double triDistance(const double* t, long nt, V3 p, double* n)
{
    double best2 = HUGE_VAL;
    V3 bestC{0, 0, 0}, bestN{0, 0, 1};
    for (long k = 0; k < nt; ++k) {
        long o = 34 * k;
        V3 s = at(t, o + 30) - p;
        double r = t[o + 33], ds = std::sqrt(dot(s, s)) - r;
        if (ds > 0 && ds * ds >= best2) continue;
        int f = 0;
        V3 q = closest(p, at(t, o), at(t, o + 3), at(t, o + 6), f);
        V3 w = p - q;
        double d2 = dot(w, w);
        if (d2 < best2) {
            best2 = d2;
            bestC = q;
            bestN = f == 0 ? at(t, o + 9) : f <= 3 ? at(t, o + 12 + 3 * (f - 1)) : at(t, o + 21 + 3 * (f - 4));
        }
    }
    V3 w = p - bestC;
    double dist = std::sqrt(best2);
    double sgn = dot(w, bestN) >= 0 ? 1.0 : -1.0;
    double nl = std::sqrt(dot(bestN, bestN));
    // the gradient: along p - q away from the surface; on it (or too close to trust p - q), the pseudo-normal
    V3 g = dist > 1e-12 * (1.0 + std::sqrt(dot(p, p))) ? (sgn / dist) * w : (1.0 / nl) * bestN;
    n[0] = g.x; n[1] = g.y; n[2] = g.z;
    return sgn * dist;
}

double wendelTriDistance(KN<double>* const& tris, KN<double>* const& y, KN<double>* const& n)
{
    const KN<double>& t = *tris;
    if (t.N() < 34 || t.N() % 34) ExecError("wendelTriDistance: the triangle table needs 34 numbers per triangle");
    if (y->N() < 3 || n->N() < 3) ExecError("wendelTriDistance: y and n need 3 components");
    double g[3];
    double d = triDistance(&t[0], t.N() / 34, V3{(*y)[0], (*y)[1], (*y)[2]}, g);
    (*n)[0] = g[0]; (*n)[1] = g[1]; (*n)[2] = g[2];
    return d;
}


// Replace the FreeFEM matrix A by the n x n matrix in CSR (rowptr, cols, vals); who names the caller in errors.
static void fricSetCsr(Matrice_Creuse<double>* A, long n, std::vector<int>& rowptr, std::vector<int>& cols,
                       std::vector<double>& vals, const char* who)
{
    A->resize(n, n);
    HashMatrix<int, double>* H = A->pHM();
    if (!H) ExecError(std::string(who) + ": the result is not a sparse matrix");
    if (A->pMC()) A->pMC()->SetSolver();
    H->set((int)n, (int)n, 0, vals.size(), rowptr.data(), cols.data(), vals.data(), 0, 1);
}

// The frame change of lib/friction.idp's Newton matrix (see the head of the file): A = L K R + B.
long wendelFricFrame(Matrice_Creuse<double>* const& A, Matrice_Creuse<double>* const& K, const long& nd,
                     KN<long>* const& dof0, KN<double>* const& fE, KN<double>* const& Pb, KN<double>* const& Hb,
                     KN<double>* const& fr)
{
    HashMatrix<int, double>* HK = K->pHM();
    if (!HK) ExecError("wendelFricFrame: K is not a sparse matrix");
    if (HK->half) ExecError("wendelFricFrame: K must be stored whole (not symmetric half)");
    if (nd < 2 || nd > 3) ExecError("wendelFricFrame: nd must be 2 or 3");
    const long n = HK->n, nc = dof0->N(), b2 = nd * nd;
    if (HK->m != n) ExecError("wendelFricFrame: K must be square");
    if (fE->N() < 9 * nc || Pb->N() < b2 * nc || Hb->N() < b2 * nc || fr->N() < nd * nc)
        ExecError("wendelFricFrame: fE needs 9, Pb and Hb nd^2, fr nd numbers per contact node");
    std::vector<int> blk(n, -1);
    std::vector<double> L(b2 * nc), R(b2 * nc), B(b2 * nc);
    for (long j = 0; j < nc; ++j) {
        const long p0 = (*dof0)[j];
        if (p0 < 0 || p0 + nd > n) ExecError("wendelFricFrame: a contact DoF is out of range");
        for (int a = 0; a < nd; ++a) {
            if (blk[p0 + a] >= 0) ExecError("wendelFricFrame: a contact node is listed twice");
            blk[p0 + a] = (int)j;
        }
        double Qt[3][3], f[3];                    // Qt[a][k] = frame vector a, component k
        for (int a = 0; a < nd; ++a) {
            f[a] = (*fr)[nd * j + a];
            for (int k = 0; k < nd; ++k) Qt[a][k] = (*fE)[9 * j + 3 * a + k];
        }
        const double* P = &(*Pb)[b2 * j];
        const double* H = &(*Hb)[b2 * j];
        for (int a = 0; a < nd; ++a)
            for (int k = 0; k < nd; ++k) {
                double l = 0, r = 0, b = 0;
                for (int c = 0; c < nd; ++c) {
                    l += P[nd * a + c] * Qt[c][k];
                    r += Qt[c][a] * f[c] * Qt[c][k];
                    b += H[nd * a + c] * f[c] * Qt[c][k];
                }
                L[b2 * j + nd * a + k] = f[a] * l;
                R[b2 * j + nd * a + k] = r;
                B[b2 * j + nd * a + k] = f[a] * b + (1.0 - f[a]) * Qt[a][k];
            }
    }
    HK->CSR();                                    // sorted by rows, row pointers p
    const int *kp = HK->p, *kj = HK->j;
    const double* ka = HK->aij;
    std::vector<int> rowptr(n + 1, 0), cols, mark(n, -1), touched;
    std::vector<double> vals, w(n, 0.0);
    cols.reserve(HK->nnz + 4 * b2 * nc);
    vals.reserve(HK->nnz + 4 * b2 * nc);
    touched.reserve(256);
    auto add = [&](int c, double v, int i) {
        if (mark[c] != i) { mark[c] = i; w[c] = 0.0; touched.push_back(c); }
        w[c] += v;
    };
    for (long i = 0; i < n; ++i) {
        touched.clear();
        const int j = blk[i];
        const long p0 = j >= 0 ? (*dof0)[j] : i;
        const int a = (int)(i - p0), ns = j >= 0 ? (int)nd : 1;
        for (int s = 0; s < ns; ++s) {
            const double coef = j >= 0 ? L[b2 * j + nd * a + s] : 1.0;
            const long r = p0 + s;
            for (int q = kp[r]; q < kp[r + 1]; ++q) {
                const int c = kj[q], jc = blk[c];
                const double v = coef * ka[q];
                if (jc < 0) { add(c, v, (int)i); continue; }
                const long q0 = (*dof0)[jc];
                const double* Rr = &R[b2 * jc + nd * (c - q0)];
                for (int e = 0; e < nd; ++e) add((int)(q0 + e), v * Rr[e], (int)i);
            }
        }
        if (j >= 0)
            for (int e = 0; e < nd; ++e) add((int)(p0 + e), B[b2 * j + nd * a + e], (int)i);
        std::sort(touched.begin(), touched.end());
        for (int c : touched) { cols.push_back(c); vals.push_back(w[c]); }
        rowptr[i + 1] = (int)cols.size();
    }
    fricSetCsr(A, n, rowptr, cols, vals, "wendelFricFrame");
    return (long)vals.size();
}

// F-bar's patch term added to the Newton matrix in one pass (lib/kinematics-fbar.idp): K = K + Dfree Y' Ds Z.
long wendelFbarAdd(Matrice_Creuse<double>* const& K, Matrice_Creuse<double>* const& Y, Matrice_Creuse<double>* const& Z,
                   KN<double>* const& sinv, KN<double>* const& fr)
{
    HashMatrix<int, double>*HK = K->pHM(), *HY = Y->pHM(), *HZ = Z->pHM();
    if (!HK || !HY || !HZ) ExecError("wendelFbarAdd: K, Y and Z must be sparse matrices");
    if (HK->half || HY->half || HZ->half) ExecError("wendelFbarAdd: the matrices must be stored whole");
    const long n = HK->n, nv = HY->n;
    if (HK->m != n || HY->m != n || HZ->m != n || HZ->n != nv)
        ExecError("wendelFbarAdd: K must be n x n, Y and Z nv x n");
    if (sinv->N() != nv || fr->N() != n) ExecError("wendelFbarAdd: sinv needs nv numbers, fr n");
    HY->CSR();
    HZ->CSR();
    HK->CSR();
    // Y' row by row (the vertices a of each DoF i, in increasing a)
    std::vector<int> tp(n + 1, 0), ta(HY->nnz);
    std::vector<double> tv(HY->nnz);
    for (long q = 0; q < HY->nnz; ++q) ++tp[HY->j[q] + 1];
    for (long i = 0; i < n; ++i) tp[i + 1] += tp[i];
    std::vector<int> fill(tp.begin(), tp.end() - 1);
    for (long a = 0; a < nv; ++a)
        for (int q = HY->p[a]; q < HY->p[a + 1]; ++q) {
            const int t = fill[HY->j[q]]++;
            ta[t] = (int)a;
            tv[t] = HY->aij[q];
        }
    std::vector<int> rowptr(n + 1, 0), cols, mark(n, -1), touched;
    std::vector<double> vals, wk(n, 0.0), wf(n, 0.0);
    cols.reserve(3 * HK->nnz);
    vals.reserve(3 * HK->nnz);
    for (long i = 0; i < n; ++i) {
        touched.clear();
        auto at = [&](int c) { if (mark[c] != i) { mark[c] = (int)i; wk[c] = 0.0; wf[c] = 0.0; touched.push_back(c); } };
        for (int q = HK->p[i]; q < HK->p[i + 1]; ++q) { at(HK->j[q]); wk[HK->j[q]] += HK->aij[q]; }
        if ((*fr)[i] != 0)
            for (int t = tp[i]; t < tp[i + 1]; ++t) {
                const int a = ta[t];
                const double y = tv[t] * (*fr)[i];
                for (int q = HZ->p[a]; q < HZ->p[a + 1]; ++q) { at(HZ->j[q]); wf[HZ->j[q]] += y * ((*sinv)[a] * HZ->aij[q]); }
            }
        std::sort(touched.begin(), touched.end());
        for (int c : touched) { cols.push_back(c); vals.push_back(wk[c] + wf[c]); }
        rowptr[i + 1] = (int)cols.size();
    }
    fricSetCsr(K, n, rowptr, cols, vals, "wendelFbarAdd");
    return (long)vals.size();
}

// Shared checks of the contact blocks' arrays (wendelFricVec, wendelFricRowsPQ).
void fricCheck(const char* who, long n, long nd, KN<long>* dof0, KN<double>* fE, KN<double>* Pb)
{
    if (nd < 2 || nd > 3) ExecError(std::string(who) + ": nd must be 2 or 3");
    const long nc = dof0->N();
    if (fE->N() < 9 * nc || Pb->N() < nd * nd * nc) ExecError(std::string(who) + ": fE needs 9, Pb nd^2 numbers per contact node");
    for (long j = 0; j < nc; ++j)
        if ((*dof0)[j] < 0 || (*dof0)[j] + nd > n) ExecError(std::string(who) + ": a contact DoF is out of range");
}

long fricVec(Matrice_Creuse<double>* K, long mode, long nd, KN<long>* dof0, KN<double>* fE, KN<double>* Pb,
             KN<double>* Hb, KN<double>* x, KN<double>* y)
{
    const long n = x->N(), nc = dof0->N(), b2 = nd * nd;
    fricCheck("wendelFricVec", n, nd, dof0, fE, mode == 1 ? Pb : fE);
    if (mode == 1 && Hb->N() < b2 * nc) ExecError("wendelFricVec: Hb needs nd^2 numbers per contact node");
    std::vector<double> xv(n), z(n);
    for (long i = 0; i < n; ++i) xv[i] = (*x)[i];
    if (mode == 0) {
        z = xv;
        for (long j = 0; j < nc; ++j) {
            const long p0 = (*dof0)[j];
            for (int a = 0; a < nd; ++a) {
                double w = 0;
                for (int k = 0; k < nd; ++k) w += (*fE)[9 * j + 3 * a + k] * xv[p0 + k];
                z[p0 + a] = w;
            }
        }
    } else if (mode == 1) {
        HashMatrix<int, double>* HK = K->pHM();
        if (!HK) ExecError("wendelFricVec: K is not a sparse matrix");
        if (HK->half || HK->n != n || HK->m != n) ExecError("wendelFricVec: K must be whole and n x n with n = x's size");
        std::vector<double> q = xv;                       // Q x
        for (long j = 0; j < nc; ++j) {
            const long p0 = (*dof0)[j];
            for (int k = 0; k < nd; ++k) {
                double w = 0;
                for (int a = 0; a < nd; ++a) w += (*fE)[9 * j + 3 * a + k] * xv[p0 + a];
                q[p0 + k] = w;
            }
        }
        HK->CSR();
        const int *kp = HK->p, *kj = HK->j;
        const double* ka = HK->aij;
        for (long i = 0; i < n; ++i) {
            double s = 0;
            for (int t = kp[i]; t < kp[i + 1]; ++t) s += ka[t] * q[kj[t]];
            z[i] = s;
        }
        for (long j = 0; j < nc; ++j) {
            const long p0 = (*dof0)[j];
            double w[3], r[3];
            for (int c = 0; c < nd; ++c) {
                w[c] = 0;
                for (int k = 0; k < nd; ++k) w[c] += (*fE)[9 * j + 3 * c + k] * z[p0 + k];
            }
            for (int a = 0; a < nd; ++a) {
                r[a] = 0;
                for (int c = 0; c < nd; ++c)
                    r[a] += (*Pb)[b2 * j + nd * a + c] * w[c] + (*Hb)[b2 * j + nd * a + c] * xv[p0 + c];
            }
            for (int a = 0; a < nd; ++a) z[p0 + a] = r[a];
        }
    } else ExecError("wendelFricVec: mode must be 0 (Q' x) or 1 ((P Q' K Q + H) x)");
    y->resize(n);
    for (long i = 0; i < n; ++i) (*y)[i] = z[i];
    return n;
}

long wendelFricQt(const long& nd, KN<long>* const& dof0, KN<double>* const& fE, KN<double>* const& x,
                  KN<double>* const& y)
{
    return fricVec(0, 0, nd, dof0, fE, fE, fE, x, y);
}

long wendelFricKl(Matrice_Creuse<double>* const& K, const long& nd, KN<long>* const& dof0, KN<double>* const& fE,
                  KN<double>* const& Pb, KN<double>* const& Hb, KN<double>* const& x, KN<double>* const& y)
{
    return fricVec(K, 1, nd, dof0, fE, Pb, Hb, x, y);
}

long wendelFricRowsPQ(Matrice_Creuse<double>* const& M, const long& n, const long& nd, KN<long>* const& dof0,
                      KN<double>* const& fE, KN<double>* const& Pb)
{
    const long nc = dof0->N(), b2 = nd * nd;
    fricCheck("wendelFricRowsPQ", n, nd, dof0, fE, Pb);
    std::vector<int> blk(n, -1);
    for (long j = 0; j < nc; ++j)
        for (int a = 0; a < nd; ++a) blk[(*dof0)[j] + a] = (int)j;
    std::vector<int> rowptr(n + 1, 0), cols;
    std::vector<double> vals;
    cols.reserve(n + b2 * nc); vals.reserve(n + b2 * nc);
    for (long i = 0; i < n; ++i) {
        const int j = blk[i];
        if (j < 0) { cols.push_back((int)i); vals.push_back(1.0); }
        else {
            const long p0 = (*dof0)[j];
            const int a = (int)(i - p0);
            for (int k = 0; k < nd; ++k) {
                double w = 0;
                for (int c = 0; c < nd; ++c) w += (*Pb)[b2 * j + nd * a + c] * (*fE)[9 * j + 3 * c + k];
                cols.push_back((int)(p0 + k)); vals.push_back(w);
            }
        }
        rowptr[i + 1] = (int)cols.size();
    }
    fricSetCsr(M, n, rowptr, cols, vals, "wendelFricRowsPQ");
    return (long)vals.size();
}

// ---- lib/friction.idp's residual pass (wendelFricResidual, wendelFricMass): see the head of the file.
// The expressions follow tool.idp and friction.idp term by term (same order of operations), so that the
// compiled pass gives the FreeFEM language's numbers to the last bit where the libm calls agree.

// x^2 as the FreeFEM language computes it: libm's pow(x, 2.), which differs from x * x in the last bit now and
// then; through a volatile pointer, since the compiler would otherwise turn pow(x, 2.) into x * x.
double (*volatile libPow)(double, double) = std::pow;
inline double sq(double x) { return libPow(x, 2.0); }

// out = R(th) v about the unit axis a (tool.idp's toolRotate).
inline void toolRotate(const double* a, const double* v, double th, double* out)
{
    double c = std::cos(th), s = std::sin(th), a0 = a[0], a1 = a[1], a2 = a[2];
    double av = a0 * v[0] + a1 * v[1] + a2 * v[2];
    out[0] = c * v[0] + s * (a1 * v[2] - a2 * v[1]) + (1 - c) * av * a0;
    out[1] = c * v[1] + s * (a2 * v[0] - a0 * v[2]) + (1 - c) * av * a1;
    out[2] = c * v[2] + s * (a0 * v[1] - a1 * v[0]) + (1 - c) * av * a2;
}

// The point X pulled back to the placement at load factor 0 (tool.idp's toolPullBack); pl = ox, oy, oz, theta.
inline void toolPullBack(const KN<double>& tool, const double* X, const double* pl, double* y)
{
    const double* c = &tool[4];
    double w[3] = {X[0] - c[0] - pl[0], X[1] - c[1] - pl[1], X[2] - c[2] - pl[2]};
    toolRotate(&tool[8], w, -pl[3], y);
    y[0] += c[0]; y[1] += c[1]; y[2] += c[2];
}

// Signed distance and gradient n0 at y (placement 0), curvature kap (tool.idp's toolDistance0).
double toolDistance0(const KN<double>& tool, const double* y, double* n0, double& kap)
{
    const int obstacle = (int)tool[0], dim = (int)tool[1], axis = (int)tool[2];
    const double dir = tool[3], *c = &tool[4], R = tool[7];
    double yx = y[0], yy = y[1];
    n0[0] = n0[1] = n0[2] = 0;
    kap = 0;
    if (obstacle == 1) {
        n0[axis] = -dir;
        return -dir * (y[axis] - c[axis]);
    }
    if (obstacle == 2) {
        double r[3] = {y[0] - c[0], y[1] - c[1], y[2] - c[2]};
        if (dim == 2) r[2] = 0;
        double rl = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (rl == 0) { n0[axis] = -dir; return -R; }
        for (int k = 0; k < 3; ++k) n0[k] = r[k] / rl;
        if (dim == 2) kap = 1. / rl;
        return rl - R;
    }
    if (tool[11] != 0) {
        const long o = 13 + 13 * (long)tool[12];
        return triDistance(&tool[o], (tool.N() - o) / 34, V3{y[0], y[1], y[2]}, n0);
    }
    const long nv = (long)tool[12];
    double best = 1e300, sgn = 1, kp = 0;
    for (long k = 0; k < nv; ++k) {
        const double* g = &tool[13 + 13 * k];
        const double tsAx = g[0], tsAy = g[1], tsBx = g[2], tsBy = g[3], tsNx = g[4], tsNy = g[5];
        const double tcX = g[6], tcY = g[7], tcR = g[8], tn1x = g[9], tn1y = g[10], tn2x = g[11], tn2y = g[12];
        double ex = tsBx - tsAx, ey = tsBy - tsAy, l2 = sq(ex) + sq(ey);
        double s = l2 > 0 ? ((yx - tsAx) * ex + (yy - tsAy) * ey) / l2 : 0;
        if (s >= 0 && s <= 1) {
            double dist = (yx - tsAx) * tsNx + (yy - tsAy) * tsNy;
            if (std::fabs(dist) < best) { best = std::fabs(dist); sgn = dist >= 0 ? 1 : -1; n0[0] = tsNx; n0[1] = tsNy; kp = 0; }
        }
        double wx = yx - tcX, wy = yy - tcY, r = std::sqrt(sq(wx) + sq(wy));
        if (tcR > 0) {
            bool inRange = (tn1x * wy - tn1y * wx) >= 0 && (wx * tn2y - wy * tn2x) >= 0;
            if (inRange && r > 0 && std::fabs(r - tcR) < best) {
                best = std::fabs(r - tcR); sgn = r >= tcR ? 1 : -1; n0[0] = wx / r; n0[1] = wy / r; kp = 1. / r;
            }
        }
        else if (r > 0 && r < best) {
            double side = wx * (tn1x + tn2x) + wy * (tn1y + tn2y);
            best = r; sgn = side >= 0 ? 1 : -1; n0[0] = sgn * wx / r; n0[1] = sgn * wy / r; kp = 0;
        }
    }
    if (dim == 2) kap = kp;
    return sgn * best;
}

const long kFricState = 9, kFricOut = 35, kFricTotals = 8;

long wendelFricResidual(KN<double>* const& toolp, KN<double>* const& parp, KN<long>* const& dof0,
                        KN<double>* const& u, KN<double>* const& u0, KN<double>* const& res,
                        KN<double>* const& statep, KN<double>* const& out)
{
    const KN<double>& tool = *toolp;
    const KN<double>& par = *parp;
    const KN<double>& st = *statep;
    if (tool.N() < 13) ExecError("wendelFricResidual: tool needs at least 13 numbers");
    const int obstacle = (int)tool[0], dim = (int)tool[1], axis = (int)tool[2];
    if (dim < 2 || dim > 3) ExecError("wendelFricResidual: tool[1] (dimension) must be 2 or 3");
    if (obstacle != 1 && obstacle != 2 && obstacle != 5) ExecError("wendelFricResidual: tool[0] (obstacle) must be 1, 2 or 5");
    if (axis < 0 || axis >= dim) ExecError("wendelFricResidual: tool[2] (contact axis) out of range");
    if (tool[12] < 0 || tool.N() < 13 + 13 * (long)tool[12]) ExecError("wendelFricResidual: tool needs 13 numbers per polygon vertex");
    if (obstacle == 5 && tool[11] == 0 && tool[12] < 3) ExecError("wendelFricResidual: a polygon tool needs nv >= 3");
    if (obstacle == 5 && tool[11] != 0) {
        const long nt = tool.N() - 13 - 13 * (long)tool[12];
        if (nt < 4 * 34 || nt % 34) ExecError("wendelFricResidual: the triangle table needs 34 numbers per triangle");
    }
    if (par.N() < 16) ExecError("wendelFricResidual: par needs 16 numbers");
    const long nc = dof0->N(), n = res->N();
    if (st.N() < kFricState * nc) ExecError("wendelFricResidual: state needs 9 numbers per contact node");
    if (u->N() != n || u0->N() != n) ExecError("wendelFricResidual: u, u0 and res must have the same size");
    for (long j = 0; j < nc; ++j)
        if ((*dof0)[j] < 0 || (*dof0)[j] + dim > n) ExecError("wendelFricResidual: a contact DoF is out of range");
    const double* pl = &par[0];
    const double* plOld = &par[4];
    const int law = (int)par[8];
    if (law < 0 || law > 2) ExecError("wendelFricResidual: par[8] (law) must be 0, 1 or 2");
    const double mu = par[9], tau = par[10], cN = par[11], ct0 = par[12], ctPred = par[13], heatFr = par[14], dirTol = par[15];
    const double dirC = tool[3];
    out->resize(kFricOut * nc + kFricTotals);
    KN<double>& o = *out;
    o = 0.;
    long cActive = 0, cEnter = 0, cLeave = 0, nStick = 0, nSlip = 0, nChanged = 0, nSetChanged = 0;
    double press = 0;
    for (long j = 0; j < nc; ++j) {
        const long p0 = (*dof0)[j];
        double* w = &o[kFricOut * j];
        const double* sj = &st[kFricState * j];
        const double setOld = sj[3], *sOld = sj + 4, m = sj[7], boundOld = sj[8];
        double X[3] = {0, 0, 0}, Xo[3] = {0, 0, 0};
        for (int k = 0; k < dim; ++k) {
            X[k] = sj[k] + (*u)[p0 + k];
            Xo[k] = sj[k] + (*u0)[p0 + k];
        }
        // toolState: distance, normal and slip relative to the tool, in world axes
        double yo[3], y[3], n0[3], nrm[3], vv[3], kap = 0;
        toolPullBack(tool, Xo, plOld, yo);
        toolPullBack(tool, X, pl, y);
        const double d = toolDistance0(tool, y, n0, kap);
        toolRotate(&tool[8], n0, pl[3], nrm);
        double dy[3] = {y[0] - yo[0], y[1] - yo[1], y[2] - yo[2]};
        toolRotate(&tool[8], dy, pl[3], vv);
        w[20] = kap;
        // fricFrame: 2D t = (-n_y, n_x); 3D t1 from the axis least aligned with n, t2 = n x t1
        double* E = w;
        for (int k = 0; k < 3; ++k) E[k] = nrm[k];
        if (dim == 2) { E[3] = -nrm[1]; E[4] = nrm[0]; E[5] = 0; }
        else {
            int mi = 0;
            for (int k = 1; k < 3; ++k) if (std::fabs(nrm[k]) < std::fabs(nrm[mi])) mi = k;
            double t[3] = {0, 0, 0};
            t[mi] = 1;
            double dn = t[0] * nrm[0] + t[1] * nrm[1] + t[2] * nrm[2];
            t[0] -= dn * nrm[0]; t[1] -= dn * nrm[1]; t[2] -= dn * nrm[2];
            double tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            for (int k = 0; k < 3; ++k) { t[k] /= tl; E[3 + k] = t[k]; }
            E[6] = nrm[1] * t[2] - nrm[2] * t[1];
            E[7] = nrm[2] * t[0] - nrm[0] * t[2];
            E[8] = nrm[0] * t[1] - nrm[1] * t[0];
        }
        double rn = 0;
        for (int k = 0; k < dim; ++k) { w[10 + k] = (*res)[p0 + k]; rn += nrm[k] * (*res)[p0 + k]; }
        const double lamN = rn / m;
        double heat = 0;
        const double ct = (ctPred > 0 && setOld > 0.5 && setOld < 1.5) ? ctPred : ct0;
        w[30] = ct;
        double zt[2] = {0, 0};
        for (int a = 1; a < dim; ++a) {
            double rt = 0, va = 0;
            for (int k = 0; k < dim; ++k) { rt += E[3 * a + k] * (*res)[p0 + k]; va += E[3 * a + k] * vv[k]; }
            w[14 + a - 1] = rt; w[16 + a - 1] = rt / m; w[18 + a - 1] = va;
            zt[a - 1] = -rt / m + ct * va;
            heat -= rt * va;
        }
        const double zl = std::sqrt(zt[0] * zt[0] + zt[1] * zt[1]);
        w[9] = d; w[13] = rn;
        const double zn = lamN - cN * d;
        int set = 0;
        double F = 0, sv[3] = {0, 0, 0};
        if (zn > 0) {
            bool capped = false;
            if (law == 1) { F = mu * zn; if (tau > 0 && F > tau) { F = tau; capped = true; } }
            else if (law == 2) F = tau;
            if (F > 0 && zl <= F) set = 1;
            else {
                set = (law == 1 && !capped) ? 2 : 3;
                for (int a = 1; a < dim; ++a)
                    for (int k = 0; k < 3; ++k) sv[k] += (zl > 0 ? zt[a - 1] / zl : (a == 1 ? 1. : 0.)) * E[3 * a + k];
            }
            double back = sv[0] * sOld[0] + sv[1] * sOld[1] + sv[2] * sOld[2];
            if (F > 0 && set >= 2 && setOld > 1.5 && back < 0) { set = 1; sv[0] = sv[1] = sv[2] = 0; }
        }
        w[21] = set; w[22] = set == 3 ? F : 0;
        w[23] = (set >= 2 && zl > 0) ? F / zl : 0;
        double dirChange = 0;
        for (int k = 0; k < 3; ++k) { dirChange = std::max(dirChange, std::fabs(sv[k] - sOld[k])); w[24 + k] = sv[k]; }
        if (set != setOld || (set >= 2 && dirChange > dirTol)) ++nChanged;
        if (set != setOld) ++nSetChanged;
        if (set > 0) ++cActive;
        if (set > 0 && setOld < 0.5) ++cEnter;
        if (set == 0 && setOld > 0.5) ++cLeave;
        if (set == 1) ++nStick;
        if (set >= 2) ++nSlip;
        w[31] = lamN; w[32] = -d; w[33] = set > 0; w[34] = heatFr * heat;
        press -= dirC * (*res)[p0 + axis];
        for (int k = 0; k < 3; ++k) w[27 + k] = (set >= 2 && setOld > 1.5) ? sv[k] : sOld[k];
        // fricRows(j, fSet, fSMerit, fBound): the rows of the last solve's sets
        if (setOld < 0.5) {
            (*res)[p0] = rn;
            for (int a = 1; a < dim; ++a) (*res)[p0 + a] = w[14 + a - 1];
        }
        else {
            (*res)[p0] = m * cN * d;
            for (int a = 1; a < dim; ++a) {
                const double sa = w[27] * E[3 * a] + w[28] * E[3 * a + 1] + w[29] * E[3 * a + 2];
                if (setOld < 1.5) (*res)[p0 + a] = m * ct0 * w[18 + a - 1];
                else if (setOld < 2.5) (*res)[p0 + a] = w[14 + a - 1] + mu * sa * rn;
                else (*res)[p0 + a] = w[14 + a - 1] + m * sa * boundOld;
            }
        }
    }
    double* t = &o[kFricOut * nc];
    t[0] = cActive; t[1] = cEnter; t[2] = cLeave; t[3] = nStick; t[4] = nSlip; t[5] = nChanged; t[6] = nSetChanged;
    t[7] = press;
    return nc;
}

long wendelFricMass(const long& dim, KN<long>* const& be, KN<double>* const& beX, KN<long>* const& jOf,
                    KN<double>* const& u, KN<double>* const& m)
{
    if (dim < 2 || dim > 3) ExecError("wendelFricMass: dim must be 2 or 3");
    const long ne = be->N() / dim, nv = jOf->N(), nc = m->N();
    if (be->N() % dim) ExecError("wendelFricMass: be needs dim vertices per element");
    if (beX->N() < 3 * be->N()) ExecError("wendelFricMass: beX needs 3 numbers per element vertex");
    if (u->N() < dim * nv) ExecError("wendelFricMass: u needs dim numbers per vertex of jOf");
    for (long q = 0; q < be->N(); ++q) {
        const long i = (*be)[q];
        if (i < 0 || i >= nv) ExecError("wendelFricMass: a boundary vertex is out of range");
        if ((*jOf)[i] >= nc) ExecError("wendelFricMass: a contact node index is out of m's range");
    }
    *m = 0.;
    for (long e = 0; e < ne; ++e) {
        double Y[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
        for (int a = 0; a < dim; ++a)
            for (int k = 0; k < dim; ++k) Y[3 * a + k] = (*beX)[3 * (dim * e + a) + k] + (*u)[dim * (*be)[dim * e + a] + k];
        double w = 0;
        if (dim == 2) w = std::sqrt(sq(Y[3] - Y[0]) + sq(Y[4] - Y[1])) / 2;
        else {
            double ax = Y[3] - Y[0], ay = Y[4] - Y[1], az = Y[5] - Y[2], bx = Y[6] - Y[0], by = Y[7] - Y[1], bz = Y[8] - Y[2];
            w = std::sqrt(sq(ay * bz - az * by) + sq(az * bx - ax * bz) + sq(ax * by - ay * bx)) / 6;
        }
        for (int a = 0; a < dim; ++a) {
            const long j = (*jOf)[(*be)[dim * e + a]];
            if (j >= 0) (*m)[j] += w;
        }
    }
    return ne;
}

}  // namespace

static void Load_Init()
{
    Global.Add("wendelTriDistance", "(",
               new OneOperator3_<double, KN<double>*, KN<double>*, KN<double>*>(wendelTriDistance));
    Global.Add("wendelFricFrame", "(",
               new OneOperator8_<long, Matrice_Creuse<double>*, Matrice_Creuse<double>*, long, KN<long>*,
                                 KN<double>*, KN<double>*, KN<double>*, KN<double>*>(wendelFricFrame));
    Global.Add("wendelFricQt", "(",
               new OneOperator5_<long, long, KN<long>*, KN<double>*, KN<double>*, KN<double>*>(wendelFricQt));
    Global.Add("wendelFricKl", "(",
               new OneOperator8_<long, Matrice_Creuse<double>*, long, KN<long>*, KN<double>*, KN<double>*,
                                 KN<double>*, KN<double>*, KN<double>*>(wendelFricKl));
    Global.Add("wendelFricResidual", "(",
               new OneOperator8_<long, KN<double>*, KN<double>*, KN<long>*, KN<double>*, KN<double>*, KN<double>*,
                                 KN<double>*, KN<double>*>(wendelFricResidual));
    Global.Add("wendelFricMass", "(",
               new OneOperator6_<long, long, KN<long>*, KN<double>*, KN<long>*, KN<double>*, KN<double>*>(wendelFricMass));
    Global.Add("wendelFbarAdd", "(",
               new OneOperator5_<long, Matrice_Creuse<double>*, Matrice_Creuse<double>*, Matrice_Creuse<double>*,
                                 KN<double>*, KN<double>*>(wendelFbarAdd));
    Global.Add("wendelFricRowsPQ", "(",
               new OneOperator6_<long, Matrice_Creuse<double>*, long, long, KN<long>*, KN<double>*,
                                 KN<double>*>(wendelFricRowsPQ));
}
LOADFUNC(Load_Init)
