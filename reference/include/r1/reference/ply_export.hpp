// An epoch as a 3D Gaussian Splatting .ply file, the INRIA layout that splat viewers read
// (R1-RND-095..097).
#pragma once

#include <cstddef>
#include <string>

#include "r1/spec/epoch.hpp"

namespace r1 {

// Opacity of every splat: the renderer's T3 splat opacity, so a splat viewer composites the
// particles as r1 draws them. Stored as logit(kSplatOpacity), the form 3DGS viewers expect.
inline constexpr double kSplatOpacity = 0.9;

// sigma = kSplatSigmaPerRadius * radius: the particle's bounding sphere holds 2 sigma of its
// Gaussian, the extent the renderer gives a splat.
inline constexpr double kSplatSigmaPerRadius = 0.5;

// Smallest sigma written: radii are > 0 (r0 sqrt(phi), phi > 0), but ln(0) would be -inf, which
// no viewer handles; 1e-6 scene units is far below a pixel at any sane zoom.
inline constexpr double kSplatMinSigma = 1e-6;

// Y_0^0 = 1 / (2 sqrt(pi)), the degree-0 real spherical harmonic: 3DGS stores a colour c in
// [0, 1] as f_dc = (c - 0.5) / kShC0 and viewers invert it.
inline constexpr double kShC0 = 0.28209479177387814;

// Floats per vertex: x y z, nx ny nz, f_dc_0..2, f_rest_0..44, opacity, scale_0..2, rot_0..3.
inline constexpr std::size_t kPlyFloatsPerVertex = 62;

// The whole file in memory: ASCII header, then one little-endian row of kPlyFloatsPerVertex
// IEEE floats per particle in canonical order. Expects an epoch as read_epoch returns it (every
// per-particle array as long as frame.position).
std::string ply_bytes(const Epoch& e);

}  // namespace r1
