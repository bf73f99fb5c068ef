// wendel_step.hpp: the elementwise helpers of the .idp array code as the operations on one value, so that a
// compiled loop that uses them gives the array code's results bit for bit (wendel_plast.cpp, wendel_ul.cpp).
#pragma once
#include <cmath>

// 1 where x > 0, else 0, as (x + |x|) / (2 |x| + 1e-300) (plastStep of lib/plasticity.idp, ulStep of
// lib/kinematics.idp)
inline double wendelStep(double x)
{
    double a = std::fabs(x);
    double o = x + a;
    a *= 2.;
    a += 1e-300;
    return o / a;
}

// max(x, 0) as (x + |x|) / 2 (plastPos of lib/plasticity.idp)
inline double wendelPos(double x)
{
    double a = std::fabs(x);
    double o = x + a;
    return o * 0.5;
}
