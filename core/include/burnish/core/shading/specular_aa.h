// Geometric specular anti-aliasing by normal-based NDF filtering: the curvature a pixel's footprint
// covers, measured by the screen-space derivatives of the shading normal, widens the lobe by a
// Gaussian kernel. The shader computes the derivatives (dFdx/dFdy); these functions take them as
// arguments so the CPU and the GLSL twin (resources/shaders/geometric_aa.glsl) compute the same.
#pragma once

#include <burnish/core/shading/ndf.h>
#include <burnish/core/util/numeric.h>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <string_view>

namespace burnish {

/// Variance σ² of the pixel filter kernel in pixels² (σ = 0.5 px).
// Tokuyoshi & Kaplanyan 2019, "Improved Geometric Specular Antialiasing", §4: σ = 0.5
inline constexpr double kSpecularAaKernelVariance = 0.25;
/// Largest roughness² the kernel may add: bounds the error of derivative estimates on 2×2 quads.
// Tokuyoshi & Kaplanyan 2019 (after Kaplanyan et al. 2016): κ = 0.18
inline constexpr double kSpecularAaKappa = 0.18;

/// The roughness² the filter kernel adds, from the squared lengths of the normal's screen-space
/// derivatives (dn2 = |∂n/∂x|² + |∂n/∂y|²): min(2σ²·dn2, κ), in [0, κ].
/// NaN or negative derivatives count as 0 (no curvature), +inf as the clamp κ.
// Tokuyoshi & Kaplanyan 2019, Listing 2: kernelRoughness2 = min(2σ²(|dndu|² + |dndv|²), κ)
template <class T>
inline T specularAaKernelRoughness2(T dn2, T sigma2 = T(kSpecularAaKernelVariance),
                                    T kappa = T(kSpecularAaKappa)) {
    const T d2 = dn2 > T(0) ? dn2 : T(0); // NaN fails d2 > 0
    const T s2 = sigma2 > T(0) ? sigma2 : T(0);
    const T k = kappa > T(0) ? kappa : T(0);
    return std::min(T(2) * s2 * d2, k);
}

/// |∂n/∂x|² + |∂n/∂y|² of two derivative vectors.
template <class T> inline T normalDerivative2(const glm::vec<3, T>& dndx, const glm::vec<3, T>& dndy) {
    return glm::dot(dndx, dndx) + glm::dot(dndy, dndy);
}

/// Filtered roughness² (GGX α² or Beckmann m², which add the same way since both are twice the
/// per-axis slope variance): saturate(α² + kernel roughness²). NaN α² is treated as 0.
// Tokuyoshi & Kaplanyan 2019, eq. 1: ᾱ² = α² + min(2σ²(‖Δn_u‖² + ‖Δn_v‖²), κ), clamped to 1
template <class T> inline T specularAaRoughness2(T alpha2, T dn2) {
    return saturate(saturate(alpha2) + specularAaKernelRoughness2(dn2));
}

/// Filtered GGX α from α and the normal's screen-space derivatives.
template <class T>
inline T specularAaGgxAlpha(T alpha, const glm::vec<3, T>& dndx, const glm::vec<3, T>& dndy) {
    return std::sqrt(specularAaRoughness2(alpha * alpha, normalDerivative2(dndx, dndy)));
}

/// Filtered Beckmann m from m and the normal's screen-space derivatives (the Beckmann NDF is a
/// Gaussian in slope space, so the convolution is exact there).
// Tokuyoshi & Kaplanyan 2019, §3: A = diag(α²) + 2Σ for the Beckmann NDF
template <class T> inline T specularAaBeckmannM(T m, const glm::vec<3, T>& dndx, const glm::vec<3, T>& dndy) {
    return std::sqrt(specularAaRoughness2(m * m, normalDerivative2(dndx, dndy)));
}

/// Filtered Blinn-Phong power: n converted to α² = 2/(n+2), filtered, and back. The power never
/// grows; where the kernel reaches κ it is at most 2/κ − 2 ≈ 9.1.
template <class T> inline T specularAaPower(T n, const glm::vec<3, T>& dndx, const glm::vec<3, T>& dndy) {
    const T alpha2 = T(2) / (clampPower(n) + T(2));
    return powerFromGgxAlpha(std::sqrt(specularAaRoughness2(alpha2, normalDerivative2(dndx, dndy))));
}

// ---------------------------------------------------------------------------------------------
// The term as a choice (render's feature set, the command line, evaluate and fit name it).

/// The geometric specular AA a shader applies (the functions above).
enum class SpecularAa { None, KaplanyanValient, TokuyoshiKaplanyan };
/// The term's name on the command line, in projects and in reports.
inline std::string_view specularAaName(SpecularAa aa) {
    switch (aa) {
    case SpecularAa::None:
        return "none";
    case SpecularAa::KaplanyanValient:
        return "kaplanyan-valient";
    case SpecularAa::TokuyoshiKaplanyan:
        return "tokuyoshi-kaplanyan";
    }
    return "none";
}

} // namespace burnish
