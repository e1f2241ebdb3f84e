// Exact Fresnel reflectance for unpolarised light (average of s and p polarisations; Born & Wolf,
// Principles of Optics, Sec. 1.5.2; for absorbing media Sec. 14.2 with a complex index).
#pragma once

#include <complex>

#include "lib/core/math.h"
#include "lib/core/spectrum.h"

namespace tb {

// Dielectric interface. cos_i: cosine between the incident direction and the normal on the
// incident side (its sign is ignored); eta = eta_transmitted / eta_incident. Returns 1 on total
// internal reflection. Symmetric: F(cos_i, eta) = F(cos_t, 1/eta).
double fresnel_dielectric(double cos_i, double eta);

// Conductor with complex relative index eta + i k (metal over the outside medium).
double fresnel_conductor(double cos_i, std::complex<double> eta);
Rgb fresnel_conductor(double cos_i, const Rgb& eta, const Rgb& k);

}  // namespace tb
