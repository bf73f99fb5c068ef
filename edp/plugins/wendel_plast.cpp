// wendel_plast: the Johnson-Cook return mapping of lib/plasticity.idp (plastReturn, law 2 without the adiabatic
// temperature) as one compiled loop over the quadrature points. The array code does each step of the algorithm
// as one FreeFEM operation on arrays of all points and iterates the scalar Newton of every point until the
// largest |g| of all is below the tolerance (22 rounds of some 45 array operations each, with four logarithms
// and powers per point and round, in an increment of the FE cut: 9 ms a residual at 3,600 cells, most of it the
// interpreter's cost per operation). This loop does the same floating-point operations in the same order per
// point, skips the points that do not yield (their increment stays 0 in the array code too) and keeps the joint
// stopping test, so that its results are the array code's bit for bit (tests/test_compiled_bit_for_bit.py).
//
// Registered in the FreeFEM language (load "wendel_plast"):
//
//   long wendelJcReturn(real[int] par, real[int] pin, real[int] eps, real[int] epspOld, real[int] pout,
//                       real[int] sig, real[int] epsp, real[int] nrm);
//       par = [mu, kappa, A, B, n, C, rate0, dt, local tol, sigma_ref, local maxit, frozen (1: the rate factors
//       of pin's third block), reg tangent]; pin = [pOld, Tfac(, rf)] (n points each); eps, epspOld Mandel,
//       component-major (nS n values, nS = eps.n / n); out (resized): pout = [p, sy, th2mu, g2mu, plastic, dp]
//       (6 n), sig, epsp, nrm (nS n). Returns the scalar Newton rounds (plastReturn's its), -1 when they did
//       not reach the tolerance.
#include "ff++.hpp"
#include "AFunction_ext.hpp"
#include "wendel_step.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace {

struct Jc {
    double mu, kappa, A, B, n, C, rate0, dt, tol, sref, reg;
    long maxit;
    bool frozen;
};

// plastYield of law 2 (not adiabatic) at one point: sy and d sy / d dp at p = pp, increment dp
inline void yield(const Jc& j, double pp, double dp, double tfac, double rfKept, double& sy, double& dsy)
{
    double lp = pp;
    lp += 1e-300;
    lp = std::log(lp);
    double w = j.n * lp;
    double hard = std::exp(w);
    w = (j.n - 1.) * lp;
    double dhard = std::exp(w);
    dhard *= j.B * j.n;
    hard *= j.B;
    hard += j.A;
    double rf = 1., drf = 0.;
    if (j.frozen)
        rf = rfKept;
    else if (j.dt > 0 && j.C > 0) {
        w = dp;
        w *= 1. / (j.dt * j.rate0);
        w -= 1.;
        double m = wendelStep(w);
        rf = wendelPos(w);
        rf += 1.;
        rf = std::log(rf);
        rf *= j.C;
        rf += 1.;
        w = dp;
        w += 1e-300;
        drf = m / w;
        drf *= j.C;
    }
    sy = hard * rf;
    sy = sy * tfac;
    dsy = dhard * rf;
    w = hard * drf;
    dsy += w;
    dsy = dsy * tfac;
}

long wendelJcReturn(KN<double>* const& par, KN<double>* const& pin, KN<double>* const& pe, KN<double>* const& peo,
                    KN<double>* const& pout, KN<double>* const& psig, KN<double>* const& pepsp,
                    KN<double>* const& pnrm)
{
    const KN<double>& P = *par;
    if (P.N() < 13) ExecError("wendelJcReturn: par needs 13 values");
    Jc j;
    j.mu = P[0]; j.kappa = P[1]; j.A = P[2]; j.B = P[3]; j.n = P[4]; j.C = P[5]; j.rate0 = P[6]; j.dt = P[7];
    j.tol = P[8]; j.sref = P[9]; j.maxit = (long)P[10]; j.frozen = P[11] > 0.5; j.reg = P[12];
    const KN<double>& in = *pin;
    const KN<double>& eps = *pe;
    const KN<double>& epo = *peo;
    const long nb = j.frozen ? 3 : 2;
    const long n = in.N() / nb;
    if (n * nb != in.N() || n == 0 || eps.N() % n != 0 || epo.N() != eps.N())
        ExecError("wendelJcReturn: pin, eps and epspOld do not hold the same points");
    const long nS = eps.N() / n;
    if (nS != 4 && nS != 6) ExecError("wendelJcReturn: 4 (2D) or 6 (3D) Mandel components");
    pout->resize(6 * n);
    psig->resize(nS * n);
    pepsp->resize(nS * n);
    pnrm->resize(nS * n);
    KN<double>& out = *pout;
    KN<double>& sig = *psig;
    KN<double>& epsp = *pepsp;
    KN<double>& nrm = *pnrm;
    const double mu2 = 2. * j.mu, mu3 = 3. * j.mu, third = 1. / 3., s15 = std::sqrt(1.5);
    const double onMu3 = 1. / mu3, yieldTol = 1e-12 * j.sref, gTol = j.tol * j.sref, keep = 1. - j.reg;
    std::vector<double> tr(n), sn(n), qtr(n), ftrs(n), plastic(n), dp(n, 0.), dsy(n, 0.), str(nS * n);
    std::vector<long> act;                  // the yielding points
    auto kept = [&](long k) { return j.frozen ? in[2 * n + k] : 1.; };     // the rate factor plastYield keeps
    for (long k = 0; k < n; ++k) {
        double t = 0.;
        for (int c = 0; c < 3; ++c) {
            t += eps[c * n + k];
            t -= epo[c * n + k];
        }
        tr[k] = t;
        double s = 0.;
        for (int c = 0; c < nS; ++c) {
            double w = eps[c * n + k];
            w -= epo[c * n + k];
            if (c < 3) w -= third * t;
            w *= mu2;
            str[c * n + k] = w;
            s += w * w;
        }
        s = std::sqrt(s);
        sn[k] = s;
        qtr[k] = s15 * s;
        double sy, d;
        yield(j, in[k], 0., in[n + k], kept(k), sy, d);
        const double ftr = qtr[k] - sy;
        ftrs[k] = ftr;
        plastic[k] = wendelStep(ftr - yieldTol);
        if (plastic[k] != 0.) act.push_back(k);
        dp[k] = wendelPos(ftr) * plastic[k];
        dp[k] *= onMu3;
    }
    // the scalar Newton of every yielding point, bracketed, stopped together (plastReturn's loop)
    const long na = act.size();
    std::vector<double> lo(na, 0.), hi(na), glo(na), ghi(na, -1e-300), g(na);
    for (long a = 0; a < na; ++a) {
        const long k = act[a];
        hi[a] = dp[k];
        glo[a] = ftrs[k];
    }
    long its = -1;
    for (long it = 0; it < j.maxit; ++it) {
        // the largest |g| as KN::linfty takes it over all points in order (s = std::max(|g_k|, s); the points that
        // do not yield have g = 0, which matters only after a NaN: std::max(0, NaN) is 0)
        double gmax = 0.;
        long prev = -1;
        for (long a = 0; a < na; ++a) {
            const long k = act[a];
            if (k > prev + 1) gmax = std::max(0., gmax);
            prev = k;
            double syl, d;
            yield(j, in[k] + dp[k], dp[k], in[n + k], kept(k), syl, d);
            dsy[k] = d;
            double gg = qtr[k] - syl;
            gg -= mu3 * dp[k];
            gg = gg * plastic[k];
            g[a] = gg;
            gmax = std::max(std::fabs(gg), gmax);
        }
        if (n > prev + 1) gmax = std::max(0., gmax);
        if (gmax <= gTol) {
            its = it;
            break;
        }
        for (long a = 0; a < na; ++a) {
            const long k = act[a];
            const double gg = g[a], x = dp[k];
            double mpos = wendelStep(gg);
            double w = x - lo[a];
            w = w * mpos;
            lo[a] += w;
            w = hi[a] - x;
            w = w * mpos;
            hi[a] = x + w;
            w = gg - glo[a];
            w = w * mpos;
            glo[a] += w;
            w = ghi[a] - gg;
            w = w * mpos;
            ghi[a] = gg + w;
            w = dsy[k];
            w += mu3;
            double newt = gg / w;
            newt += x;
            double inside = wendelStep(newt - lo[a]);
            mpos = wendelStep(hi[a] - newt);
            inside = inside * mpos;
            double mid = glo[a] - ghi[a];
            mid += 1e-300;
            w = hi[a] - lo[a];
            w = w * glo[a];
            mid = w / mid;
            mid += lo[a];
            w = newt - mid;
            w = w * inside;
            double y = mid + w;
            dp[k] = y * plastic[k];
        }
    }
    // radial return and the consistent tangent
    for (long k = 0; k < n; ++k) {
        double w = qtr[k];
        w += 1e-300;
        double beta = dp[k] / w;
        beta *= mu3;
        double th = -beta;
        th += 1.;
        th *= mu2;
        w = dsy[k];
        w += mu3;
        double gm = mu3 / w;
        gm -= beta;
        gm = gm * plastic[k];
        gm *= mu2;
        w = keep * th;
        w -= gm;
        const double w2 = wendelPos(w);
        gm = keep * th;
        gm -= w2;
        const double snr = sn[k] + 1e-300;
        for (int c = 0; c < nS; ++c) {
            const long o = c * n + k;
            double v = str[o] / snr;
            nrm[o] = v;
            v = v * dp[k];
            v *= s15;
            v += epo[o];
            epsp[o] = v;
            v = str[o];
            v -= v * beta;
            if (c < 3) v += j.kappa * tr[k];
            sig[o] = v;
        }
        const double p = in[k] + dp[k];
        double sy, d;
        yield(j, p, dp[k], in[n + k], kept(k), sy, d);
        out[k] = p;
        out[n + k] = sy;
        out[2 * n + k] = th;
        out[3 * n + k] = gm;
        out[4 * n + k] = plastic[k];
        out[5 * n + k] = dp[k];
    }
    return its;
}

}  // namespace

static void Load_Init()
{
    Global.Add("wendelJcReturn", "(",
               new OneOperator8_<long, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*, KN<double>*,
                                 KN<double>*, KN<double>*>(wendelJcReturn));
}
LOADFUNC(Load_Init)
