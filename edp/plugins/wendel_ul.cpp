// wendel_ul: compiled per-cell kernels of the updated-Lagrangian kinematics (edp/lib/kinematics.idp,
// kinematics-3d.idp). They compute per cell, in one loop, what the FreeFEM-language array code computed
// with one array operation per tensor entry (some 2,000 operations on arrays of one value per cell, each, for
// each residual of a 3D increment: at a few thousand cells the interpreter's cost per operation, not the
// arithmetic, was most of the UL-only time; 9 and 7 ms a residual at 3,072 cells, now 2.1 and 1.3 ms). Same algorithm and the same floating-point operations per cell;
// the iterations (polar decomposition, logarithm series) stop per cell on the bound the array code applied to
// all cells at once, so the results agree to round-off.
//
// Registered in the FreeFEM language (load "wendel_ul"):
//
//   long wendelUlTrial3(real[int] FFn, real[int] epsN, real[int] epspC, real[int] G, real[int] dets,
//                       real[int] epsT, real[int] pe, real[int] epspT);
//       Per cell (n = epsN.n / 6 cells; full 3x3 tensors as 9 arrays, index (i 3 + j) n + cell; Mandel vectors
//       [xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy] as 6 arrays): FFn the deformation gradients F of the trial
//       and Fn of the increment's start (18 arrays, F first); out G = F^-1, dets = [det F, detf = det F / det Fn]
//       (2 arrays), and for f = F Fn^-1 =
//       V R (R by Newton's polar iteration X <- (X + X^-T) / 2 until no entry moves by 1e-15, ln V by the
//       Gregory series 2 sum Z^(2j+1) / (2j + 1), Z = (V - I)(V + I)^-1, until a term is below 1e-18):
//       epsT = R epsN R^T + ln V, pe = epsT - sym(F - I) (the pre-strain of elasticity.idp) and, when epspC is
//       not empty, epspT = R epspC R^T. Returns the number of cells whose det f is not positive (their
//       outputs beyond G, detF and detf are left unchanged).
//   long wendelUlTangent(real[int] S, real[int] N, real[int] c, real[int] G, real[int] J, int[int] act,
//                        real[int] D, real[int] P);
//       The per-cell coefficients of the UL tangent and internal forces (ulTangent of kinematics.idp; d x d
//       tensors, d = 2 or 3 from S's size, full storage (i d + j) n + cell; act the na active gradient
//       components i d + j; c = [c1, c2, c3], 3 arrays): D_{pm,rk} = J [(c1 G_mp + Y_pm) G_kr + G_mr (c2 G_kp - Y_pk) / 2 - G_kp Y_rm / 2
//       - c3 M_pm M_rk - S_pr H_mk / 2 + d_pr (c2 H_mk + Z_mk) / 2] at (ia na + ib) n + cell and P_pm = J Y_pm
//       at ia n + cell, with Y = S G^T, M = N G^T, H = G G^T, Z = G Y. Returns n.
//   long wendelUlExact2(real[int] S, real[int] N, real[int] c, real[int] X, real[int] G, real[int] J, int[int] act,
//                       real[int] D);
//       The plane (in-plane) part of the exact derivative of the strain update (ulExact of kinematics.idp, 2D and
//       (r, z)) added to D (as wendelUlTangent's): c = [c2, c3] (2 arrays), X = [f11, f12, f21, f22, p, q, V11, V12,
//       V22, beta] of the trial (10 arrays, ulTrial); S, N, G full d x d (d = 2, or 3 in (r, z)). The array code's
//       operations in its order, per cell: the same D bit for bit (tests/test_plast_compiled.py). Returns n.
//   long wendelUlMatrix2(matrix K, mesh Th, real[int] D, real[int] fix, real[int] Fc, real[int] G, real[int] sinv);
//       The plane (2D, not (r, z)) P1 Newton matrix of the updated-Lagrangian kinematics: the varf vTangent
//       (mechanics.idp, kinematics.idp's tangentWork), K = sum over the triangles of |T| D_{pm,rn} d_m v_p d_n du_r
//       (one point: D and the P1 gradients are constant per triangle; D as wendelUlTangent's with the 4 gradient
//       components active, 16 arrays of Th.nt values) and, when Fc is not empty, F-bar's patch term of
//       kinematics-fbar.idp, Y' diag(sinv) Z on the free rows (Y and Z its varfs ulVY, ulVZ: the vertex patches'
//       sums of |T| / 3 times (Fc_(2r) d_x + Fc_(2r+1) d_y) du_r and (G_(0r) d_x + G_(1r) d_y) du_r; Fc and G 4
//       arrays of Th.nt values, sinv one value per vertex); the rows of the DoFs with fix = 1 identity rows (the
//       varf's tgv = -1). DoF 2 a + component of vertex a. The same matrix as the varfs and wendelFbarAdd to
//       round-off (other orders of the sums; kinematics.idp's -ul_tangent_compiled 2 records the difference), in
//       one pass instead of three varfs and a product. Returns the entries.
#include "ff++.hpp"
#include "AFunction_ext.hpp"
#include "wendel_step.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace {

typedef double M3[3][3];

const double s2 = std::sqrt(2.0);
const int mi[6] = {0, 1, 2, 1, 0, 0}, mj[6] = {0, 1, 2, 2, 2, 1};

void load9(const KN<double>& a, long n, long k, M3 A)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) A[i][j] = a[(i * 3 + j) * n + k];
}
// B = A^-1 (t: A^-T) by cofactors as ulInv: C_ij = A_(i+1)(j+1) A_(i+2)(j+2) - A_(i+1)(j+2) A_(i+2)(j+1)
double inv(const M3 A, M3 B, bool t)
{
    M3 C;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            C[i][j] = A[i1][j1] * A[i2][j2] - A[i1][j2] * A[i2][j1];
        }
    double det = 0.0;
    for (int j = 0; j < 3; ++j) det += A[0][j] * C[0][j];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) B[i][j] = (t ? C[i][j] : C[j][i]) / det;
    return det;
}
// C = op(A) op(B) as ulMul (the sum over k in order)
void mul(const M3 A, const M3 B, M3 C, bool tA, bool tB)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double w = 0.0;
            for (int k = 0; k < 3; ++k) w += (tA ? A[k][i] : A[i][k]) * (tB ? B[j][k] : B[k][j]);
            C[i][j] = w;
        }
}
void fromMandel(const KN<double>& m, long n, long k, M3 A)
{
    for (int c = 0; c < 6; ++c) {
        double w = m[c * n + k];
        if (c >= 3) w *= 1.0 / s2;
        A[mi[c]][mj[c]] = w;
        A[mj[c]][mi[c]] = w;
    }
}
// Mandel vector of the symmetric part of A (ulFullToMandel)
void toMandel(const M3 A, double m[6])
{
    for (int c = 0; c < 6; ++c) {
        const int i = mi[c], j = mj[c];
        double w = A[i][j];
        if (c >= 3) { w += A[j][i]; w *= 1.0 / s2; }
        m[c] = w;
    }
}
// R M R^T of the Mandel vector at cell k (ulRotateMandel)
void rotate(const M3 R, const KN<double>& m, long n, long k, double out[6])
{
    M3 A, B;
    fromMandel(m, n, k, A);
    mul(R, A, B, false, false);
    mul(B, R, A, false, true);
    toMandel(A, out);
}

long wendelUlTrial3(KN<double>* const& pFFn, KN<double>* const& pEpsN, KN<double>* const& pEpspC,
                    KN<double>* const& pG, KN<double>* const& pDets, KN<double>* const& pEpsT, KN<double>* const& pPe,
                    KN<double>* const& pEpspT)
{
    const long n = pEpsN->N() / 6;
    const bool plast = pEpspC->N() > 0;
    if (pFFn->N() != 18 * n || pG->N() != 9 * n || pDets->N() != 2 * n || pEpsN->N() != 6 * n
        || pEpsT->N() != 6 * n || pPe->N() != 6 * n || (plast && (pEpspC->N() != 6 * n || pEpspT->N() != 6 * n)))
        ExecError("wendelUlTrial3: FFn needs 18 values per cell, G 9, epsN, epsT, pe (epspC, epspT) 6, dets 2");
    KN<double>&G = *pG, &dets = *pDets, &epsT = *pEpsT, &pe = *pPe, &epspT = *pEpspT;
    long bad = 0;
    for (long k = 0; k < n; ++k) {
        M3 F, Fn, Gi, Fni, f, X, Xi;
        load9(*pFFn, n, k, F);
        load9(*pFFn, n, 9 * n + k, Fn);
        const double dF = inv(F, Gi, false), dFn = inv(Fn, Fni, false);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) G[(i * 3 + j) * n + k] = Gi[i][j];
        const double df = dF / dFn;
        dets[k] = dF;
        dets[n + k] = df;
        if (!(df > 0)) { ++bad; continue; }
        mul(F, Fni, f, false, false);
        // polar rotation: X <- (X + X^-T) / 2
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) X[i][j] = f[i][j];
        for (int it = 0; it < 60; ++it) {
            inv(X, Xi, true);
            double move = 0.0;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    double x = Xi[i][j] + X[i][j];
                    x *= 0.5;
                    move = std::max(move, std::fabs(x - X[i][j]));
                    X[i][j] = x;
                }
            if (move < 1e-15) break;
        }
        M3 V, T, T2, Z, Z2, L;
        mul(f, X, V, false, true);                            // V = f R^T, symmetrised
        M3 Vs;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) Vs[i][j] = (V[i][j] + V[j][i]) * 0.5;
        // Z = (V - I)(V + I)^-1, ln V = 2 (Z + Z^3/3 + Z^5/5 + ...)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) T[i][j] = Vs[i][j] + (i == j ? 1.0 : 0.0);
        inv(T, T2, false);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) T[i][j] = Vs[i][j] - (i == j ? 1.0 : 0.0);
        mul(T, T2, Z, false, false);
        mul(Z, Z, Z2, false, false);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) L[i][j] = T[i][j] = Z[i][j];
        for (int jj = 1; jj < 400; ++jj) {
            mul(T, Z2, T2, false, false);
            double big = 0.0;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    T[i][j] = T2[i][j];
                    L[i][j] += (1. / (2 * jj + 1)) * T[i][j];
                    big = std::max(big, std::fabs(T[i][j]));
                }
            if (big < 1e-18) break;
        }
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) L[i][j] *= 2.;
        // eps_{n+1} = R eps_n R^T + ln V; pre-strain eps_{n+1} - sym(F - I)
        double e[6], lm[6], gm[6];
        rotate(X, *pEpsN, n, k, e);
        toMandel(L, lm);
        for (int i = 0; i < 3; ++i) F[i][i] -= 1.;
        toMandel(F, gm);
        for (int c = 0; c < 6; ++c) {
            e[c] += lm[c];
            epsT[c * n + k] = e[c];
            pe[c * n + k] = e[c] - gm[c];
        }
        if (plast) {
            rotate(X, *pEpspC, n, k, e);
            for (int c = 0; c < 6; ++c) epspT[c * n + k] = e[c];
        }
    }
    return bad;
}

long wendelUlTangent(KN<double>* const& pS, KN<double>* const& pN, KN<double>* const& pc, KN<double>* const& pG,
                     KN<double>* const& pJ, KN<long>* const& pAct, KN<double>* const& pD, KN<double>* const& pP)
{
    const long n = pJ->N(), na = pAct->N();
    const int d = (pS->N() == 9 * n) ? 3 : 2, dd = d * d;
    if (pS->N() != dd * n || pN->N() != dd * n || pG->N() != dd * n || pc->N() != 3 * n || pD->N() != na * na * n
        || pP->N() != na * n || na > dd)
        ExecError("wendelUlTangent: S, N, G need d^2 values per cell, c three, J one, D na^2, P na (na <= d^2)");
    const KN<double>&S = *pS, &N = *pN, &G = *pG, &J = *pJ;
    KN<double>&D = *pD, &P = *pP;
    int p_[81], m_[81];
    for (long a = 0; a < na; ++a) {
        const long c = (*pAct)[a];
        if (c < 0 || c >= dd) ExecError("wendelUlTangent: act entries must be in [0, d^2)");
        p_[a] = (int)(c / d);
        m_[a] = (int)(c % d);
    }
    for (long k = 0; k < n; ++k) {
        double s[3][3], nn[3][3], g[3][3], Y[3][3], M[3][3], H[3][3], Z[3][3], Q[3][3], R[3][3], B[3][3];
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) {
                const long o = (i * d + j) * n + k;
                s[i][j] = S[o];
                nn[i][j] = N[o];
                g[i][j] = G[o];
            }
        const double c1 = (*pc)[k], c2 = (*pc)[n + k], c3 = (*pc)[2 * n + k], Jk = J[k];
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) {
                double y = 0.0, m = 0.0, h = 0.0;
                for (int q = 0; q < d; ++q) {
                    y += s[i][q] * g[j][q];
                    m += nn[i][q] * g[j][q];
                    h += g[i][q] * g[j][q];
                }
                Y[i][j] = y;
                M[i][j] = m;                                // M_rk: the plain N G^T
                H[i][j] = h;
            }
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j) {
                double z = 0.0;
                for (int q = 0; q < d; ++q) z += g[i][q] * Y[q][j];
                Z[i][j] = z;
                Q[i][j] = g[j][i] * c1 + Y[i][j];
                R[i][j] = (g[i][j] * c2 - Y[j][i]) * 0.5;
                B[i][j] = (H[i][j] * c2 + Z[i][j]) * 0.5;
            }
        for (long ia = 0; ia < na; ++ia) {
            const int p = p_[ia], m = m_[ia];
            const double cM = M[p][m] * c3;
            for (long ib = 0; ib < na; ++ib) {
                const int r = p_[ib], kk = m_[ib];
                double w = Q[p][m] * g[kk][r];
                w += g[m][r] * R[kk][p];
                w -= 0.5 * (g[kk][p] * Y[r][m]);
                w -= cM * M[r][kk];
                w -= 0.5 * (s[p][r] * H[m][kk]);
                if (p == r) w += B[m][kk];
                D[(ia * na + ib) * n + k] = w * Jk;
            }
            P[ia * n + k] = Y[p][m] * Jk;
        }
    }
    return n;
}


long wendelUlExact2(KN<double>* const& pS, KN<double>* const& pN, KN<double>* const& pc, KN<double>* const& pX,
                    KN<double>* const& pG, KN<double>* const& pJ, KN<long>* const& pact, KN<double>* const& pD)
{
    const KN<double>& S = *pS;
    const KN<double>& N = *pN;
    const KN<double>& G = *pG;
    const KN<double>& X = *pX;
    const long n = pJ->N(), na = pact->N();
    if (n == 0) return 0;
    const long d = S.N() == 4 * n ? 2 : 3;
    if (S.N() != d * d * n || N.N() != S.N() || G.N() != S.N() || pc->N() != 2 * n || X.N() != 10 * n
        || pD->N() != na * na * n)
        ExecError("wendelUlExact2: array sizes");
    KN<double>& D = *pD;
    const KN<double>& J = *pJ;
    const int comp[4] = {0, 1, 1, 2};
    std::vector<int> p_(na), m_(na);
    for (long a = 0; a < na; ++a) {
        const long c = (*pact)[a];
        p_[a] = (int)(c / d);
        m_[a] = (int)(c % d);
    }
    for (long k = 0; k < n; ++k) {
        const double f11 = X[k], f12 = X[n + k], f21 = X[2 * n + k], f22 = X[3 * n + k], p = X[4 * n + k],
                     q = X[5 * n + k], V11 = X[6 * n + k], V12 = X[7 * n + k], V22 = X[8 * n + k], be = X[9 * n + k];
        const double c2 = (*pc)[k], c3 = (*pc)[n + k];
        double w = q * q;
        double r2 = p * p;
        r2 += w;
        double vdd = V11 - V22, vm = V11 + V22;
        vdd *= 0.5;
        vm *= 0.5;
        double h2 = vdd * vdd;
        w = V12 * V12;
        h2 += w;
        double vdet = vm * vm;
        vdet -= h2;
        w = vm * vm;
        const double tq = h2 / w;
        double vga = vm / vdet;
        vga -= be;
        w = h2;
        w += 1e-300;
        vga = vga / w;
        double gs = tq;
        gs *= 6. / 7.;
        gs += 4. / 5.;
        gs = gs * tq;
        gs += 2. / 3.;
        w = vm * vm;
        w = w * vm;
        gs = gs / w;
        w = tq;
        w -= 1e-4;
        const double bg = wendelStep(w);
        vga -= gs;
        vga = vga * bg;
        vga += gs;
        double K00 = S[(0 * d + 1) * n + k];
        K00 *= -2.;
        const double K11 = -K00;
        double K01 = S[k];
        w = S[(d + 1) * n + k];
        K01 -= w;
        const double N00 = N[k], N01 = N[n + k], N11 = N[(d + 1) * n + k], N22 = d == 3 ? N[8 * n + k] : 0.;
        double dT[4][4];                      // basis (r v) = 2 r + v; components 00, 01, 11, 22
        for (int r = 0; r < 2; ++r)
            for (int v = 0; v < 2; ++v) {
                const double fv0 = v == 0 ? f11 : f21, fv1 = v == 0 ? f12 : f22;
                const double Vv0 = v == 0 ? V11 : V12, Vv1 = v == 0 ? V12 : V22;
                const double dp = r == 0 ? fv0 : fv1, dq = r == 0 ? -fv1 : fv0;
                double dth = p * dq;
                w = q * dp;
                dth -= w;
                dth = dth / r2;
                double dV00 = V12 * dth, dV01 = V11 - V22;
                dV00 = -dV00;
                double dV11 = -dV00;
                dV01 = dV01 * dth;
                if (r == 0) {
                    dV00 += Vv0;
                    dV01 += Vv1;
                }
                else {
                    dV11 += Vv1;
                    dV01 += Vv0;
                }
                dV01 *= 0.5;
                double dm = dV00 + dV11, ddd = dV00 - dV11;
                dm *= 0.5;
                ddd *= 0.5;
                double da = V22 * dV00;
                w = V11 * dV11;
                da += w;
                w = V12 * dV01;
                da -= 2. * w;
                da = da / vdet;
                da *= 0.5;
                double db = vdd * ddd;
                w = V12 * dV01;
                db += w;
                db = db * vga;
                w = dm / vdet;
                db -= w;
                const double bth = be * dth;
                double e00 = db * vdd, e01 = db * V12;
                w = be * ddd;
                e00 += w;
                double e11 = -e00;
                e00 += da;
                e11 += da;
                w = V12 * bth;
                e00 += 2. * w;
                e11 -= 2. * w;
                w = be * dV01;
                e01 += w;
                w = vdd * bth;
                e01 -= 2. * w;
                if (r == 0 && v == 0) e00 -= 1.;
                if (r == 1 && v == 1) e11 -= 1.;
                if (r != v) e01 -= 0.5;
                if (r == 1 && v == 0) dth -= 0.5;
                if (r == 0 && v == 1) dth += 0.5;
                double ne = N00 * e00;
                w = N11 * e11;
                ne += w;
                w = N01 * e01;
                ne += 2. * w;
                ne = ne * c3;
                double* t = dT[2 * r + v];
                double w2;
                w = c2 * e00; w2 = N00 * ne; w -= w2; w2 = K00 * dth; w += w2; t[0] = w;
                w = c2 * e01; w2 = N01 * ne; w -= w2; w2 = K01 * dth; w += w2; t[1] = w;
                w = c2 * e11; w2 = N11 * ne; w -= w2; w2 = K11 * dth; w += w2; t[2] = w;
                w = N22 * ne; w = -w; t[3] = w;
            }
        for (long ia = 0; ia < na; ++ia)
            for (long ib = 0; ib < na; ++ib) {
                const int pp = p_[ia], m = m_[ia], r = p_[ib], kk = m_[ib];
                if (r == 2) continue;             // the hoop column: exact already
                w = 0.;
                for (int qq = 0; qq < d; ++qq) {
                    if ((pp == 2) != (qq == 2)) continue;
                    const int c = pp == 2 ? 3 : comp[2 * pp + qq];
                    for (int v = 0; v < 2; ++v) {
                        double w2 = dT[2 * r + v][c];
                        w2 = w2 * G[(m * d + qq) * n + k];
                        w2 = w2 * G[(kk * d + v) * n + k];
                        w += w2;
                    }
                }
                w = w * J[k];
                D[(ia * na + ib) * n + k] += w;
            }
    }
    return n;
}


// The CSR pattern of the Newton matrix of the P1 vector space of a 2D mesh (2 DoFs a vertex, DoF 2 a + c): with
// F-bar every pair of DoFs of two vertices that share a vertex patch (the patch term couples a patch's DoFs: the
// vertices at most two edges apart), else every pair of a triangle's vertices. Kept with its addresses for the
// next call on the same triangles (the Newton steps of a launch, whose mesh moves but keeps its triangles):
// tri[9 k + 3 i + j], where vertex j's block sits in vertex i's row of triangle k; for each vertex a, its patch
// (the vertices of its triangles, sorted) and pair[q], where patch vertex jj's block sits in patch vertex ii's row.
struct Pattern2 {
    long nv = -1, nt = -1;
    bool fbar = false;
    uint64_t key = 0;
    std::vector<int> rowptr, col, tri;
    std::vector<int> patchPtr, patch, pairPtr, pair, cellPtr, cell;
} pat2;

uint64_t triangles(const Mesh& Th)
{
    uint64_t h = 1469598103934665603ull;
    for (long k = 0; k < Th.nt; ++k)
        for (int i = 0; i < 3; ++i) h = (h ^ (uint64_t)Th(Th[k][i])) * 1099511628211ull;
    return h;
}

int where(const std::vector<int>& cols, int lo, int hi, int b)     // the block of vertex b in [lo, hi) (in vertices)
{
    return (int)(std::lower_bound(cols.begin() + lo, cols.begin() + hi, b) - cols.begin()) - lo;
}

void ensurePattern2(const Mesh& Th, bool fbar)
{
    const uint64_t key = triangles(Th);
    if (pat2.nv == Th.nv && pat2.nt == Th.nt && pat2.key == key && pat2.fbar == fbar) return;
    const long nv = Th.nv, nt = Th.nt;
    std::vector<std::vector<int>> nb(nv), cells(nv);
    for (long k = 0; k < nt; ++k)
        for (int i = 0; i < 3; ++i) {
            cells[Th(Th[k][i])].push_back((int)k);
            for (int j = 0; j < 3; ++j) nb[Th(Th[k][i])].push_back(Th(Th[k][j]));
        }
    for (auto& v : nb) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
    }
    std::vector<std::vector<int>> row(nv);          // the vertices of each vertex's row
    for (long a = 0; a < nv; ++a) {
        if (!fbar) { row[a] = nb[a]; continue; }
        for (int b : nb[a]) row[a].insert(row[a].end(), nb[b].begin(), nb[b].end());
        std::sort(row[a].begin(), row[a].end());
        row[a].erase(std::unique(row[a].begin(), row[a].end()), row[a].end());
    }
    std::vector<int> vptr(nv + 1, 0), vcol;          // the rows in vertices
    for (long a = 0; a < nv; ++a) {
        vptr[a + 1] = vptr[a] + (int)row[a].size();
        vcol.insert(vcol.end(), row[a].begin(), row[a].end());
    }
    pat2.rowptr.assign(2 * nv + 1, 0);
    for (long a = 0; a < nv; ++a)
        for (int c = 0; c < 2; ++c) pat2.rowptr[2 * a + c + 1] = pat2.rowptr[2 * a + c] + 2 * (int)row[a].size();
    pat2.col.resize(pat2.rowptr[2 * nv]);
    for (long a = 0; a < nv; ++a)
        for (int c = 0; c < 2; ++c) {
            int q = pat2.rowptr[2 * a + c];
            for (int b : row[a]) { pat2.col[q++] = 2 * b; pat2.col[q++] = 2 * b + 1; }
        }
    pat2.tri.resize(9 * nt);
    for (long k = 0; k < nt; ++k)
        for (int i = 0; i < 3; ++i) {
            const int a = Th(Th[k][i]);
            for (int j = 0; j < 3; ++j) pat2.tri[9 * k + 3 * i + j] = where(vcol, vptr[a], vptr[a + 1], Th(Th[k][j]));
        }
    pat2.patchPtr.assign(nv + 1, 0);
    pat2.pairPtr.assign(nv + 1, 0);
    pat2.cellPtr.assign(nv + 1, 0);
    pat2.patch.clear();
    pat2.pair.clear();
    pat2.cell.clear();
    if (fbar)
        for (long a = 0; a < nv; ++a) {
            pat2.patch.insert(pat2.patch.end(), nb[a].begin(), nb[a].end());
            pat2.patchPtr[a + 1] = (int)pat2.patch.size();
            for (int bi : nb[a])
                for (int bj : nb[a]) pat2.pair.push_back(where(vcol, vptr[bi], vptr[bi + 1], bj));
            pat2.pairPtr[a + 1] = (int)pat2.pair.size();
            pat2.cell.insert(pat2.cell.end(), cells[a].begin(), cells[a].end());
            pat2.cellPtr[a + 1] = (int)pat2.cell.size();
        }
    pat2.nv = nv;
    pat2.nt = nt;
    pat2.key = key;
    pat2.fbar = fbar;
}

long wendelUlMatrix2(Matrice_Creuse<double>* const& K, const Mesh* const& pTh, KN<double>* const& pD,
                     KN<double>* const& fix, KN<double>* const& pFc, KN<double>* const& pG, KN<double>* const& sinv)
{
    const Mesh& Th = *pTh;
    const long nt = Th.nt, nv = Th.nv, n = 2 * nv;
    const KN<double>& D = *pD;
    const bool fbar = pFc->N() > 0;
    if (D.N() != 16 * nt) ExecError("wendelUlMatrix2: D needs 16 values per triangle");
    if (fix->N() != n) ExecError("wendelUlMatrix2: fix needs one value per DoF (2 per vertex)");
    if (fbar && (pFc->N() != 4 * nt || pG->N() < 4 * nt || sinv->N() != nv))
        ExecError("wendelUlMatrix2: F-bar needs Fc and G with 4 values per triangle, sinv one per vertex");
    ensurePattern2(Th, fbar);
    std::vector<double> val(pat2.col.size(), 0.0);
    std::vector<double> grad(6 * nt);            // the barycentric gradients, g[i][m] at 6 k + 2 i + m
    for (long k = 0; k < nt; ++k) {
        const Triangle& T = Th[k];
        const double area = T.area;
        double* g = &grad[6 * k];
        for (int i = 0; i < 3; ++i) {
            const R2 h = T.H(i);
            g[2 * i] = h.x;
            g[2 * i + 1] = h.y;
        }
        double Dk[16];
        for (int q = 0; q < 16; ++q) Dk[q] = area * D[q * nt + k];
        const int* off = &pat2.tri[9 * k];
        for (int i = 0; i < 3; ++i) {
            const int a = Th(T[i]);
            for (int j = 0; j < 3; ++j) {
                const int o = 2 * off[3 * i + j];
                for (int p = 0; p < 2; ++p) {
                    double* row = &val[pat2.rowptr[2 * a + p] + o];
                    for (int r = 0; r < 2; ++r) {
                        const double* d = &Dk[8 * p + 2 * r];      // D_{pm,rn} at 8 p + 4 m + 2 r + n
                        row[r] += g[2 * i] * (d[0] * g[2 * j] + d[1] * g[2 * j + 1])
                                  + g[2 * i + 1] * (d[4] * g[2 * j] + d[5] * g[2 * j + 1]);
                    }
                }
            }
        }
    }
    if (fbar) {      // + Y' diag(sinv) Z on the free rows: Y(a, (b, r)) = sum_(k at a, b) |k| / 3 q_k(b, r), Z likewise w_k
        const KN<double>& Fc = *pFc;
        const KN<double>& G = *pG;
        std::vector<double> y, z;
        for (long a = 0; a < nv; ++a) {
            const int p0 = pat2.patchPtr[a], np = pat2.patchPtr[a + 1] - p0;
            y.assign(2 * np, 0.0);
            z.assign(2 * np, 0.0);
            for (int t = pat2.cellPtr[a]; t < pat2.cellPtr[a + 1]; ++t) {
                const long k = pat2.cell[t];
                const Triangle& T = Th[k];
                const double w = T.area / 3.0, *g = &grad[6 * k];
                for (int i = 0; i < 3; ++i) {
                    const int bi = (int)(std::lower_bound(pat2.patch.begin() + p0, pat2.patch.begin() + p0 + np,
                                                          (int)Th(T[i])) - pat2.patch.begin()) - p0;
                    for (int r = 0; r < 2; ++r) {
                        y[2 * bi + r] += w * (Fc[(2 * r) * nt + k] * g[2 * i] + Fc[(2 * r + 1) * nt + k] * g[2 * i + 1]);
                        z[2 * bi + r] += w * (G[r * nt + k] * g[2 * i] + G[(2 + r) * nt + k] * g[2 * i + 1]);
                    }
                }
            }
            const double s = (*sinv)[a];
            const int* pr = &pat2.pair[pat2.pairPtr[a]];
            for (int ii = 0; ii < np; ++ii) {
                const int bi = pat2.patch[p0 + ii];
                for (int c = 0; c < 2; ++c) {
                    const double yc = y[2 * ii + c];
                    if ((*fix)[2 * bi + c] > 0.5 || yc == 0.0) continue;
                    double* row = &val[pat2.rowptr[2 * bi + c]];
                    for (int jj = 0; jj < np; ++jj) {
                        const int o = 2 * pr[ii * np + jj];
                        row[o] += yc * (s * z[2 * jj]);
                        row[o + 1] += yc * (s * z[2 * jj + 1]);
                    }
                }
            }
        }
    }
    for (long r = 0; r < n; ++r)
        if ((*fix)[r] > 0.5)
            for (int q = pat2.rowptr[r]; q < pat2.rowptr[r + 1]; ++q) val[q] = pat2.col[q] == r ? 1.0 : 0.0;
    K->resize(n, n);
    HashMatrix<int, double>* H = K->pHM();
    if (!H) ExecError("wendelUlMatrix2: K is not a sparse matrix");
    H->set((int)n, (int)n, 0, val.size(), pat2.rowptr.data(), pat2.col.data(), val.data(), 0, 1);
    return (long)val.size();
}

}  // namespace

static void Load_Init()
{
    Global.Add("wendelUlTrial3", "(",
               new OneOperator8_<long, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*,
                                 KN<double>*, KN<double>*>(wendelUlTrial3));
    Global.Add("wendelUlTangent", "(",
               new OneOperator8_<long, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<long>*,
                                 KN<double>*, KN<double>*>(wendelUlTangent));
    Global.Add("wendelUlMatrix2", "(",
               new OneOperator7_<long, Matrice_Creuse<double>*, const Mesh*, KN<double>*, KN<double>*, KN<double>*,
                                 KN<double>*, KN<double>*>(wendelUlMatrix2));
    Global.Add("wendelUlExact2", "(",
               new OneOperator8_<long, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*,
                                 KN<long>*, KN<double>*>(wendelUlExact2));
}
LOADFUNC(Load_Init)
