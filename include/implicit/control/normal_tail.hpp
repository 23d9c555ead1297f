#pragma once
// Logarithms of standard normal probabilities that stay accurate far in the tails.
//
// Path integral control of problems with hard walls needs log(Phi(b) - Phi(a)) for intervals
// many standard deviations from the mean (the double slit at t close to the wall time). Computing
// Phi(b) - Phi(a) in double precision and then taking the log cancels catastrophically: at
// (x, t) = (1, 0.5) of the double slit the naive difference gives u = -0.625 instead of -10.14.
//
//   double lp = implicit::control::log_normal_interval(a, b);   // log P(a < Z < b), Z ~ N(0,1)
//   double lc = implicit::control::log_normal_cdf(-40.0);       // -804.6..., no underflow
//
// Common mistake: using std::log(std::erfc(...)) below z = -37, where erfc underflows to 0.

namespace implicit::control {

/// log Phi(z), Phi the standard normal cdf; accurate for every finite z (asymptotic series
/// below z = -30, log1p above z = 5). Returns -inf at z = -inf and 0 at z = +inf.
double log_normal_cdf(double z);

/// log phi(z) = -z^2/2 - log(2 pi)/2, phi the standard normal density.
double log_normal_pdf(double z);

/// log(Phi(b) - Phi(a)) for a <= b, computed without cancellation: in the upper tail through
/// the survival function, in the lower tail through the cdf. -inf when a >= b.
double log_normal_interval(double a, double b);

}  // namespace implicit::control
