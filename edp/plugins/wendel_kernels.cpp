// wendel_kernels: compiled element kernels of the small-strain J2 Newton step on 3D P1 tetrahedra
// (numerics.assembly = "compiled"; edp/lib/kernels.idp). The .edp keeps the algorithm (Newton, line search,
// return mapping, contact, solver); these functions replace three FreeFEM-language integrals of it, with
// the one-point rule that lib/plasticity.idp uses for P1 (qfV1: the centroid, weight = volume; exact for P1).
//
// Registered in the FreeFEM language (load "wendel_kernels"):
//
//   long nnz = wendelTangent3(matrix K, mesh3 Th, real[int] th2mu, real[int] g2mu, real[int] nrm, real kappa,
//                             real[int] fix);
//       K = the consistent J2 tangent, the integral over Th of
//           kappa div(du) div(v) + th2mu (eps(du) : eps(v) - div(du) div(v) / 3) - g2mu (n : eps(du)) (n : eps(v)),
//       th2mu, g2mu one value per tetrahedron, nrm the unit flow direction n (Mandel [xx, yy, zz, sqrt2 yz,
//       sqrt2 xz, sqrt2 xy], component-major: 6 arrays of nt values); the rows with fix > 0.5 are zeroed
//       with 1 on the diagonal (FreeFEM's tgv = -1). DoFs of [P1, P1, P1]: 3 vertex + component.
//   long wendelStrain3(mesh3 Th, real[int] u, real[int] eps);
//       eps (resized to 6 nt) = Mandel strain of the P1 displacement u per tetrahedron, component-major; after
//       wendelPart3 on 2+ ranks, of this rank's tetrahedra only (the others' entries 0).
//   long wendelInternal3(mesh3 Th, real[int] sig, real[int] f);
//       f (resized to 3 nv) = the integral of sig : eps(v) (sig Mandel per tetrahedron, component-major).
//   long wendelPart3(mesh3 Th, long rank, long size, real[int] order);
//       Rank-local assembly on `size` MPI ranks: the vertices sorted along the axis of the bounding box's
//       largest extent are cut into `size` slabs of equal vertex counts; `order` (resized to 3 nv) gets the
//       global (PETSc) index of every DoF, 3 (slab-ordered vertex) + component, so that rank r's rows are the
//       r-th contiguous block, and within a slab the vertices keep the mesh's numbering (not the coordinate
//       order: the rows keep the locality of the mesh's numbering, as on one rank); a tetrahedron belongs to
//       the rank of the lowest slab among its vertices. From then on
//       wendelTangent3 and wendelInternal3 sum over this rank's tetrahedra only (K and f are this rank's
//       parts: the sum over the ranks is the whole), and wendelTangent3 leaves the fixed rows to the solver
//       (no 1 on their diagonal). size 1 undoes it. Returns the number of this rank's tetrahedra.
//   long wendelPartPoints(mesh3 Th, long ncomp, int[int] idx);
//       idx (resized to ncomp times this rank's tetrahedron count) = c nt + k for every component c < ncomp
//       and every tetrahedron k of this rank (wendelPart3), component-major, k ascending: the positions of
//       this rank's quadrature points in a component-major array of ncomp nt values (one point per
//       tetrahedron). Every tetrahedron when not partitioned. Returns idx's size.
//
// The CSR pattern of K (every vertex pair of a tetrahedron, 3 x 3 blocks, sorted columns) and the position
// of each tetrahedron's blocks in it are kept for the last mesh (its address, vertex and element counts).
#include "ff++.hpp"
#include "AFunction_ext.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace {

struct Pattern {
    const Mesh3* mesh = nullptr;
    long nv = -1, nt = -1;
    std::vector<int> vptr, vcol;     // vertex graph: neighbours of vertex a (itself included), sorted
    std::vector<int> rowptr, col;    // DoF CSR (3 rows per vertex, 3 columns per neighbour)
    std::vector<int> off;            // per tetrahedron, 16 entries: index of vertex b in a's neighbour list
};
Pattern pat;
std::vector<char> own;               // wendelPart3: 1 for this rank's tetrahedra; empty = every tetrahedron
const Mesh3* ownMesh = nullptr;

const double s2 = std::sqrt(2.0);

// Is tetrahedron k assembled on this rank (wendelPart3)?
bool mine(long k) { return own.empty() || own[k]; }

void checkPart(const Mesh3& Th)
{
    if (!own.empty() && (ownMesh != &Th || (long)own.size() != Th.nt))
        ExecError("wendel_kernels: the mesh changed after wendelPart3; partition the new mesh");
}

void buildPattern(const Mesh3& Th)
{
    const long nv = Th.nv, nt = Th.nt;
    std::vector<std::vector<int>> nb(nv);
    for (long k = 0; k < nt; ++k) {
        if (!mine(k)) continue;
        const Tet& K = Th[k];
        int v[4];
        for (int i = 0; i < 4; ++i) v[i] = Th(K[i]);
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) nb[v[i]].push_back(v[j]);
    }
    pat.vptr.assign(nv + 1, 0);
    for (long a = 0; a < nv; ++a) {
        std::sort(nb[a].begin(), nb[a].end());
        nb[a].erase(std::unique(nb[a].begin(), nb[a].end()), nb[a].end());
        pat.vptr[a + 1] = pat.vptr[a] + (int)nb[a].size();
    }
    pat.vcol.resize(pat.vptr[nv]);
    for (long a = 0; a < nv; ++a) std::copy(nb[a].begin(), nb[a].end(), pat.vcol.begin() + pat.vptr[a]);
    const long n = 3 * nv;
    pat.rowptr.assign(n + 1, 0);
    pat.col.resize(9 * (size_t)pat.vptr[nv]);
    size_t pos = 0;
    for (long a = 0; a < nv; ++a)
        for (int d = 0; d < 3; ++d) {
            for (int q = pat.vptr[a]; q < pat.vptr[a + 1]; ++q)
                for (int e = 0; e < 3; ++e) pat.col[pos++] = 3 * pat.vcol[q] + e;
            pat.rowptr[3 * a + d + 1] = (int)pos;
        }
    pat.off.resize(16 * (size_t)nt);
    for (long k = 0; k < nt; ++k) {
        if (!mine(k)) continue;
        const Tet& K = Th[k];
        int v[4];
        for (int i = 0; i < 4; ++i) v[i] = Th(K[i]);
        for (int i = 0; i < 4; ++i) {
            const int* b = &pat.vcol[pat.vptr[v[i]]];
            const int* e = &pat.vcol[pat.vptr[v[i] + 1]];
            for (int j = 0; j < 4; ++j) pat.off[16 * k + 4 * i + j] = (int)(std::lower_bound(b, e, v[j]) - b);
        }
    }
    pat.mesh = &Th;
    pat.nv = nv;
    pat.nt = nt;
}

void ensurePattern(const Mesh3& Th)
{
    if (pat.mesh != &Th || pat.nv != Th.nv || pat.nt != Th.nt) buildPattern(Th);
}

// Gradients of the four barycentric coordinates of tetrahedron K (g[i][0..2]).
void gradients(const Tet& K, double g[4][3])
{
    const R3 &p0 = K[0], &p1 = K[1], &p2 = K[2], &p3 = K[3];
    const R3 e1 = p1 - p0, e2 = p2 - p0, e3 = p3 - p0;
    const R3 c1 = e2 ^ e3, c2 = e3 ^ e1, c3 = e1 ^ e2;   // rows of det * J^-1
    const double det = (e1, c1);
    const R3* c[3] = {&c1, &c2, &c3};
    for (int i = 1; i < 4; ++i) {
        g[i][0] = c[i - 1]->x / det;
        g[i][1] = c[i - 1]->y / det;
        g[i][2] = c[i - 1]->z / det;
    }
    for (int j = 0; j < 3; ++j) g[0][j] = -(g[1][j] + g[2][j] + g[3][j]);
}

// Symmetric tensor of a Mandel vector stored component-major (6 arrays of nt values) at element k.
void tensor(const KN<double>& m, long nt, long k, double T[3][3])
{
    const double a = m[k], b = m[nt + k], c = m[2 * nt + k];
    const double yz = m[3 * nt + k] / s2, xz = m[4 * nt + k] / s2, xy = m[5 * nt + k] / s2;
    T[0][0] = a;  T[0][1] = xy; T[0][2] = xz;
    T[1][0] = xy; T[1][1] = b;  T[1][2] = yz;
    T[2][0] = xz; T[2][1] = yz; T[2][2] = c;
}

long wendelTangent3(Matrice_Creuse<double>* const& K, const Mesh3* const& pTh, KN<double>* const& th2mu,
                    KN<double>* const& g2mu, KN<double>* const& nrm, const double& kappa, KN<double>* const& fix)
{
    const Mesh3& Th = *pTh;
    const long nt = Th.nt, nv = Th.nv, n = 3 * nv;
    if (th2mu->N() != nt || g2mu->N() != nt || nrm->N() != 6 * nt)
        ExecError("wendelTangent3: th2mu and g2mu need one value per tetrahedron, nrm six");
    if (fix->N() != n) ExecError("wendelTangent3: fix needs one value per DoF (3 per vertex)");
    checkPart(Th);
    ensurePattern(Th);
    std::vector<double> val(pat.col.size(), 0.0);
    double g[4][3], w[4][3], N[3][3];
    for (long k = 0; k < nt; ++k) {
        if (!mine(k)) continue;
        const Tet& T = Th[k];
        gradients(T, g);
        const double vol = T.mesure(), th = (*th2mu)[k], gm = (*g2mu)[k];
        const double cl = vol * (kappa - th / 3.0), ch = vol * 0.5 * th, cg = vol * gm;
        tensor(*nrm, nt, k, N);
        for (int i = 0; i < 4; ++i)
            for (int d = 0; d < 3; ++d) w[i][d] = N[d][0] * g[i][0] + N[d][1] * g[i][1] + N[d][2] * g[i][2];
        const int* off = &pat.off[16 * k];
        for (int i = 0; i < 4; ++i) {
            const int a = Th(T[i]);
            for (int j = 0; j < 4; ++j) {
                const double gg = g[i][0] * g[j][0] + g[i][1] * g[j][1] + g[i][2] * g[j][2];
                const int o = 3 * off[4 * i + j];
                for (int d = 0; d < 3; ++d) {
                    double* row = &val[pat.rowptr[3 * a + d] + o];
                    for (int e = 0; e < 3; ++e)
                        row[e] += cl * g[i][d] * g[j][e] + ch * ((d == e ? gg : 0.0) + g[i][e] * g[j][d])
                                  - cg * w[i][d] * w[j][e];
                }
            }
        }
    }
    for (long r = 0; r < n && own.empty(); ++r)      // parts: the solver sets the fixed rows of the sum
        if ((*fix)[r] > 0.5)
            for (int q = pat.rowptr[r]; q < pat.rowptr[r + 1]; ++q) val[q] = pat.col[q] == r ? 1.0 : 0.0;
    K->resize(n, n);
    HashMatrix<int, double>* H = K->pHM();
    if (!H) ExecError("wendelTangent3: K is not a sparse matrix");
    H->set((int)n, (int)n, 0, val.size(), pat.rowptr.data(), pat.col.data(), val.data(), 0, 1);
    return (long)val.size();
}

long wendelStrain3(const Mesh3* const& pTh, KN<double>* const& u, KN<double>* const& eps)
{
    const Mesh3& Th = *pTh;
    const long nt = Th.nt;
    if (u->N() != 3 * Th.nv) ExecError("wendelStrain3: u needs 3 values per vertex");
    eps->resize(6 * nt);
    checkPart(Th);
    if (!own.empty()) *eps = 0.0;
    double g[4][3];
    for (long k = 0; k < nt; ++k) {
        if (!mine(k)) continue;
        const Tet& T = Th[k];
        gradients(T, g);
        double G[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};   // G[c][j] = d u_c / d x_j
        for (int i = 0; i < 4; ++i) {
            const long a = Th(T[i]);
            for (int c = 0; c < 3; ++c) {
                const double uc = (*u)[3 * a + c];
                for (int j = 0; j < 3; ++j) G[c][j] += uc * g[i][j];
            }
        }
        (*eps)[k] = G[0][0];
        (*eps)[nt + k] = G[1][1];
        (*eps)[2 * nt + k] = G[2][2];
        (*eps)[3 * nt + k] = (G[1][2] + G[2][1]) / s2;
        (*eps)[4 * nt + k] = (G[0][2] + G[2][0]) / s2;
        (*eps)[5 * nt + k] = (G[0][1] + G[1][0]) / s2;
    }
    return nt;
}

long wendelInternal3(const Mesh3* const& pTh, KN<double>* const& sig, KN<double>* const& f)
{
    const Mesh3& Th = *pTh;
    const long nt = Th.nt, n = 3 * Th.nv;
    if (sig->N() != 6 * nt) ExecError("wendelInternal3: sig needs 6 values per tetrahedron");
    checkPart(Th);
    f->resize(n);
    *f = 0.0;
    double g[4][3], S[3][3];
    for (long k = 0; k < nt; ++k) {
        if (!mine(k)) continue;
        const Tet& T = Th[k];
        gradients(T, g);
        tensor(*sig, nt, k, S);
        const double vol = T.mesure();
        for (int i = 0; i < 4; ++i) {
            const long a = Th(T[i]);
            for (int d = 0; d < 3; ++d)
                (*f)[3 * a + d] += vol * (S[d][0] * g[i][0] + S[d][1] * g[i][1] + S[d][2] * g[i][2]);
        }
    }
    return n;
}

long wendelPart3(const Mesh3* const& pTh, const long& rank, const long& size, KN<double>* const& order)
{
    const Mesh3& Th = *pTh;
    const long nv = Th.nv, nt = Th.nt;
    if (size < 1 || rank < 0 || rank >= size) ExecError("wendelPart3: rank must be in [0, size)");
    pat = Pattern();                                  // the pattern follows the part
    order->resize(3 * nv);
    if (size == 1) {
        own.clear();
        ownMesh = nullptr;
        for (long i = 0; i < 3 * nv; ++i) (*order)[i] = i;
        return nt;
    }
    R3 lo = Th.vertices[0], hi = lo;
    for (long a = 0; a < nv; ++a) {
        const R3& P = Th.vertices[a];
        lo.x = std::min(lo.x, P.x); lo.y = std::min(lo.y, P.y); lo.z = std::min(lo.z, P.z);
        hi.x = std::max(hi.x, P.x); hi.y = std::max(hi.y, P.y); hi.z = std::max(hi.z, P.z);
    }
    const R3 ext = hi - lo;
    const int axis = (ext.x >= ext.y && ext.x >= ext.z) ? 0 : (ext.y >= ext.z ? 1 : 2);
    std::vector<long> byPos(nv);
    for (long a = 0; a < nv; ++a) byPos[a] = a;
    auto coord = [&Th, axis](long a) { const R3& P = Th.vertices[a]; return axis == 0 ? P.x : axis == 1 ? P.y : P.z; };
    std::stable_sort(byPos.begin(), byPos.end(), [&coord](long a, long b) { return coord(a) < coord(b); });
    // The slab of a vertex is its block of sorted positions, nv r / size <= p < nv (r + 1) / size; within its
    // slab a vertex keeps the mesh's numbering (its rank among the slab's vertices by vertex number), not the
    // coordinate order: the rows of a rank keep the locality of the mesh's numbering, as on one rank.
    std::vector<long> slab(nv), next(size), pos(nv);
    for (long r = 0; r < size; ++r) {
        next[r] = nv * r / size;
        for (long p = nv * r / size; p < nv * (r + 1) / size; ++p) slab[byPos[p]] = r;
    }
    for (long a = 0; a < nv; ++a) pos[a] = next[slab[a]]++;
    for (long a = 0; a < nv; ++a)
        for (int d = 0; d < 3; ++d) (*order)[3 * a + d] = 3 * pos[a] + d;
    const long start = nv * rank / size, end = nv * (rank + 1) / size;   // the petsc plugin's row blocks
    own.assign(nt, 0);
    long mineCount = 0;
    for (long k = 0; k < nt; ++k) {
        const Tet& T = Th[k];
        long p = pos[Th(T[0])];
        for (int i = 1; i < 4; ++i) p = std::min(p, pos[Th(T[i])]);
        if (p >= start && p < end) { own[k] = 1; ++mineCount; }
    }
    ownMesh = &Th;
    return mineCount;
}

long wendelPartPoints(const Mesh3* const& pTh, const long& ncomp, KN<long>* const& idx)
{
    const Mesh3& Th = *pTh;
    const long nt = Th.nt;
    if (ncomp < 1) ExecError("wendelPartPoints: ncomp must be >= 1");
    checkPart(Th);
    long n = 0;
    for (long k = 0; k < nt; ++k) n += mine(k);
    idx->resize(ncomp * n);
    long pos = 0;
    for (long c = 0; c < ncomp; ++c)
        for (long k = 0; k < nt; ++k)
            if (mine(k)) (*idx)[pos++] = c * nt + k;
    return ncomp * n;
}

}  // namespace

static void Load_Init()
{
    Global.Add("wendelTangent3", "(",
               new OneOperator7_<long, Matrice_Creuse<double>*, const Mesh3*, KN<double>*, KN<double>*, KN<double>*,
                                 double, KN<double>*>(wendelTangent3));
    Global.Add("wendelStrain3", "(", new OneOperator3_<long, const Mesh3*, KN<double>*, KN<double>*>(wendelStrain3));
    Global.Add("wendelInternal3", "(",
               new OneOperator3_<long, const Mesh3*, KN<double>*, KN<double>*>(wendelInternal3));
    Global.Add("wendelPart3", "(", new OneOperator4_<long, const Mesh3*, long, long, KN<double>*>(wendelPart3));
    Global.Add("wendelPartPoints", "(",
               new OneOperator3_<long, const Mesh3*, long, KN<long>*>(wendelPartPoints));
}
LOADFUNC(Load_Init)
