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
// The closest point on each triangle by its Voronoi regions (face, edge or vertex: Ericson, Real-Time
// Collision Detection, 2005, sec. 5.1.5); the sign from the pseudo-normal of the feature holding the nearest
// point (Baerentzen and Aanaes, IEEE TVCG 11, 2005: angle-weighted pseudo-normals give the right sign for
// closed manifolds). Brute force over the triangles, skipping those whose bounding sphere is farther than
// the best distance so far: O(triangles) per call, no state kept between calls.
#include "ff++.hpp"
#include "AFunction_ext.hpp"

#include <cmath>

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

}  // namespace

static void Load_Init()
{
    Global.Add("wendelTriDistance", "(",
               new OneOperator3_<double, KN<double>*, KN<double>*, KN<double>*>(wendelTriDistance));
}
LOADFUNC(Load_Init)
