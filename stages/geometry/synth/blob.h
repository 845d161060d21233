// The carved blob of the sculpture preset (objects.h's SynthBlob): a
// star-shaped implicit surface |p - c| - R(w) = 0, its radius function,
// normals, closest points and ray hits. Exactness as stated in objects.h.
// Internal to pb_synth (objects.cc is its user).
#pragma once

#include "stages/geometry/synth/objects.h"

namespace pb {

// R(w) for a unit direction w, meters; the groove profile G(w) / depth in
// [0, 1] (1 at a groove's bottom; the albedo darkens there).
double BlobRadius(const SynthBlob& blob, const Vec3& w);
double BlobGroove(const SynthBlob& blob, const Vec3& w);
// |p - c| - R(w): < 0 inside. Its gradient (unit length only on a sphere).
double BlobImplicit(const SynthBlob& blob, const Vec3& p);
Vec3 BlobGradient(const SynthBlob& blob, const Vec3& p);

struct BlobClosest {
  double distance_m = 0;  // signed, > 0 outside
  Vec3 foot{};            // the closest surface point found
  Vec3 normal{};          // unit, outward, at foot
};
BlobClosest BlobClosestPoint(const SynthBlob& blob, const Vec3& p);

// Ray parameter of the first hit of origin + t * dir (dir unit), or +inf.
double BlobRayHit(const SynthBlob& blob, const Vec3& origin, const Vec3& dir);

}  // namespace pb
