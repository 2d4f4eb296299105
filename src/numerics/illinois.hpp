// The Illinois variant of regula falsi (Dowell & Jarratt, BIT 11 (1971) 168-174) for the zero of a
// scalar function between two points where it has opposite signs: the secant point, with the
// value kept at the same end for a second time halved so that the bracket shrinks from both sides.
// Pure: standard library only.
#pragma once
#include <cmath>

namespace truss::numerics {

// g(ta) = ga and g(tb) = gb have opposite signs (or gb == 0). Returns a point on tb's side of the
// zero (g there has gb's sign or is 0) within tol of it, after at most max_iter evaluations of g.
template <class G>
double find_crossing_illinois(G&& g, double ta, double ga, double tb, double gb, double tol, int max_iter = 200) {
  int side = 0;
  for (int it = 0; it < max_iter && (tb - ta) > tol; ++it) {
    double tc = (ta * gb - tb * ga) / (gb - ga);
    if (!(tc > ta && tc < tb)) tc = 0.5 * (ta + tb);
    const double gc = g(tc);
    if ((gc > 0.0) == (gb > 0.0) && gc != 0.0) {
      tb = tc; gb = gc;
      if (side == -1) ga *= 0.5;
      side = -1;
    } else if (gc == 0.0) {
      return tc;
    } else {
      ta = tc; ga = gc;
      if (side == 1) gb *= 0.5;
      side = 1;
    }
  }
  return tb;
}

}  // namespace truss::numerics
