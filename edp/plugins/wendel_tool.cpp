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
inline V3 at(const KN<double>& t, long k) { return V3{t[k], t[k + 1], t[k + 2]}; }
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

double wendelTriDistance(KN<double>* const& tris, KN<double>* const& y, KN<double>* const& n)
{
    const KN<double>& t = *tris;
    if (t.N() < 34 || t.N() % 34) ExecError("wendelTriDistance: the triangle table needs 34 numbers per triangle");
    if (y->N() < 3 || n->N() < 3) ExecError("wendelTriDistance: y and n need 3 components");
    V3 p{(*y)[0], (*y)[1], (*y)[2]};
    long nt = t.N() / 34;
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
    (*n)[0] = g.x; (*n)[1] = g.y; (*n)[2] = g.z;
    return sgn * dist;
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
    Global.Add("wendelFricRowsPQ", "(",
               new OneOperator6_<long, Matrice_Creuse<double>*, long, long, KN<long>*, KN<double>*,
                                 KN<double>*>(wendelFricRowsPQ));
}
LOADFUNC(Load_Init)
