#include "stages/geometry/points/enclosure.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pb {
namespace {

constexpr uint8_t kFree = 0, kOccupied = 1, kOutside = 2, kEnclosed = 3, kSmall = 4;

struct Grid {
  std::array<int, 3> dims{};
  size_t Index(int x, int y, int z) const {
    return (size_t(z) * size_t(dims[1]) + size_t(y)) * size_t(dims[0]) + size_t(x);
  }
  // The voxel coordinates of index i (Index's inverse).
  std::array<int, 3> Coords(size_t i) const {
    return {int(i % size_t(dims[0])), int((i / size_t(dims[0])) % size_t(dims[1])),
            int(i / (size_t(dims[0]) * size_t(dims[1])))};
  }
  size_t size() const { return size_t(dims[0]) * size_t(dims[1]) * size_t(dims[2]); }
  size_t Stride(int axis) const {
    return axis == 0 ? 1 : axis == 1 ? size_t(dims[0]) : size_t(dims[0]) * size_t(dims[1]);
  }
};

// Sets every voxel within `radius` voxels along `axis` of a voxel equal to
// `value` to `value` (one pass of a separable cube growth); others keep theirs.
void GrowAlong(const Grid& grid, int axis, int radius, uint8_t value, std::vector<uint8_t>& cells) {
  const size_t stride = grid.Stride(axis);
  const int length = grid.dims[axis];
  std::vector<int> before(length);
  std::vector<uint8_t> line(length);
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  for (int v = 0; v < grid.dims[a2]; ++v) {
    for (int u = 0; u < grid.dims[a1]; ++u) {
      std::array<int, 3> start{};
      start[a1] = u;
      start[a2] = v;
      const size_t first = grid.Index(start[0], start[1], start[2]);
      for (int i = 0; i < length; ++i) line[i] = cells[first + size_t(i) * stride] == value;
      // Distance to the nearest marked voxel before and after each one.
      int last = -1 - radius;
      for (int i = 0; i < length; ++i) {
        if (line[i]) last = i;
        before[i] = i - last;
      }
      int next = length + radius;
      for (int i = length - 1; i >= 0; --i) {
        if (line[i]) next = i;
        if (std::min(before[i], next - i) <= radius) cells[first + size_t(i) * stride] = value;
      }
    }
  }
}

void Grow(const Grid& grid, int radius, uint8_t value, std::vector<uint8_t>& cells) {
  for (int axis = 0; axis < 3; ++axis) GrowAlong(grid, axis, radius, value, cells);
}

// Visits the 6-connected voxels equal to `from` reachable from `queue`'s
// voxels (already set to `to`), setting them to `to`; returns how many.
size_t Fill(const Grid& grid, uint8_t from, uint8_t to, std::vector<uint32_t>& queue,
            std::vector<uint8_t>& cells) {
  size_t head = 0;
  while (head < queue.size()) {
    const uint32_t i = queue[head++];
    const std::array<int, 3> coords = grid.Coords(i);
    for (int axis = 0; axis < 3; ++axis) {
      for (int step : {-1, 1}) {
        const int c = coords[axis] + step;
        if (c < 0 || c >= grid.dims[axis]) continue;
        const size_t j = step < 0 ? i - grid.Stride(axis) : i + grid.Stride(axis);
        if (cells[j] != from) continue;
        cells[j] = to;
        queue.push_back(uint32_t(j));
      }
    }
  }
  return queue.size();
}

// The grid over the cloud's robust box, the voxels holding a point, and
// those grown by the gap.
struct Voxels {
  Grid grid;
  std::vector<uint8_t> scanned;  // kOccupied where a point lies, else kFree
  std::vector<uint8_t> cells;    // scanned grown by `radius` voxels
  int radius = 0;                // the gap in voxels
};

// Voxels of `gap_m` / 4, or coarser to fit max_voxels_per_side.
Expected<Voxels> Prepare(const PointCloud& cloud, const EnclosureOptions& options, double gap_m,
                         std::array<double, 3>& min, double& voxel) {
  if (cloud.empty()) return Status::Invalid("enclosed space: the cloud has no points");
  if (!(options.gap_m > 0) || !(options.min_volume_m3 > 0) || !(options.open_gap_m > 0) ||
      !(options.min_open_volume_m3 > 0) || !(options.min_surrounded > 0 && options.min_surrounded <= 1) ||
      options.max_voxels_per_side < 16)
    return Status::Invalid(
        "enclosed space: gap_m, open_gap_m and the volumes must be positive, min_surrounded in (0, 1]");
  PB_RETURN_IF_ERROR(CheckFinitePositions(cloud, "enclosed space"));
  const float* positions = cloud.positions.data();
  const Bounds robust = RobustLocalBounds(cloud, 0.005);
  const std::array<double, 3>& lo = robust.min_m;
  const std::array<double, 3>& hi = robust.max_m;
  const double longest = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double margin = 0.02 * longest + gap_m;
  voxel = std::max(gap_m / 4, (longest + 2 * margin) / double(options.max_voxels_per_side - 4));
  Voxels v;
  for (int axis = 0; axis < 3; ++axis) {
    min[axis] = lo[axis] - margin - 2 * voxel;
    v.grid.dims[axis] = std::max(3, int(std::ceil((hi[axis] - lo[axis] + 2 * margin + 4 * voxel) / voxel)));
    v.grid.dims[axis] = std::min(v.grid.dims[axis], options.max_voxels_per_side);
  }
  v.scanned.assign(v.grid.size(), kFree);
  for (size_t i = 0; i < cloud.size(); ++i) {
    int c[3];
    bool in = true;
    for (int axis = 0; axis < 3; ++axis) {
      const double f = std::floor((positions[3 * i + axis] - min[axis]) / voxel);
      in = in && f >= 0 && f < v.grid.dims[axis];
      c[axis] = in ? int(f) : 0;
    }
    if (in) v.scanned[v.grid.Index(c[0], c[1], c[2])] = kOccupied;
  }
  v.radius = std::max(1, int(std::ceil(gap_m / voxel - 1e-9)));
  v.cells = v.scanned;
  Grow(v.grid, v.radius, kOccupied, v.cells);
  return v;
}

// Marks each 6-connected part of kFree voxels kEnclosed when it holds at
// least `min_volume_m3` and `accept` takes its voxels, else kSmall (too
// small) or kOutside (refused); returns the voxels marked kEnclosed.
template <typename Accept>
size_t KeepLargeParts(const Grid& grid, double voxel, double min_volume_m3, std::vector<uint8_t>& cells,
                      Accept accept) {
  const double voxel_volume = voxel * voxel * voxel;
  std::vector<uint32_t> queue;
  size_t enclosed = 0;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i] != kFree) continue;
    queue.assign(1, uint32_t(i));
    cells[i] = kSmall;
    const size_t count = Fill(grid, kFree, kSmall, queue, cells);
    if (double(count) * voxel_volume < min_volume_m3) continue;
    const bool accepted = accept(queue);
    for (uint32_t j : queue) cells[j] = accepted ? kEnclosed : kOutside;
    if (!accepted) continue;
    enclosed += count;
  }
  return enclosed;
}

struct LinesOfSight {
  std::vector<uint8_t> meeting;  // per voxel, of the 26 directions
  std::vector<uint8_t> leaving;  // per voxel, bit a * 2 + (d > 0): the axis direction leaves
};

// For every voxel, how many of the 26 lattice directions (a voxel's
// neighbours') lead from it into an occupied voxel before the grid's border,
// and which of the six along the axes do not. One sweep per direction, each
// voxel taking its neighbour's answer.
LinesOfSight LinesOfSightMeetingTheScan(const Grid& grid, const std::vector<uint8_t>& cells) {
  LinesOfSight lines;
  lines.meeting.assign(cells.size(), 0);
  lines.leaving.assign(cells.size(), 0);
  std::vector<uint8_t>& count = lines.meeting;
  std::vector<uint8_t> meets(cells.size(), 0);
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const int d[3] = {dx, dy, dz};
        // Visit each voxel after its neighbour along d.
        for (int zi = 0; zi < grid.dims[2]; ++zi) {
          const int z = dz > 0 ? grid.dims[2] - 1 - zi : zi;
          for (int yi = 0; yi < grid.dims[1]; ++yi) {
            const int y = dy > 0 ? grid.dims[1] - 1 - yi : yi;
            for (int xi = 0; xi < grid.dims[0]; ++xi) {
              const int x = dx > 0 ? grid.dims[0] - 1 - xi : xi;
              const int nx = x + d[0], ny = y + d[1], nz = z + d[2];
              const size_t i = grid.Index(x, y, z);
              if (nx < 0 || ny < 0 || nz < 0 || nx >= grid.dims[0] || ny >= grid.dims[1] || nz >= grid.dims[2]) {
                meets[i] = 0;
                continue;
              }
              const size_t j = grid.Index(nx, ny, nz);
              meets[i] = cells[j] == kOccupied || meets[j];
              count[i] = uint8_t(count[i] + meets[i]);
            }
          }
        }
        if (std::abs(dx) + std::abs(dy) + std::abs(dz) != 1) continue;
        const int axis = dx != 0 ? 0 : dy != 0 ? 1 : 2;
        const uint8_t bit = uint8_t(1u << (2 * axis + (d[axis] > 0 ? 1 : 0)));
        for (size_t i = 0; i < cells.size(); ++i) {
          if (!meets[i]) lines.leaving[i] |= bit;
        }
      }
    }
  }
  return lines;
}

}  // namespace

// The deepest voxel of the parts marked kEnclosed in `cells` (on the grid
// dims_), and the space reaching back from them to the scan
// (`outside_radius`: the growth that made `cells`' occupancy).
void EnclosedSpace::Finish(std::vector<uint8_t>& cells, const std::vector<uint8_t>& scanned, int outside_radius) {
  const Grid grid{dims_};
  const double voxel = voxel_m_;
  // The deepest enclosed voxel: city-block distance to the nearest voxel
  // outside the parts, by a forward and a backward pass.
  std::vector<uint16_t> depth(cells.size(), 0);
  for (size_t i = 0; i < cells.size(); ++i) depth[i] = cells[i] == kEnclosed ? std::numeric_limits<uint16_t>::max() : 0;
  for (int pass = 0; pass < 2; ++pass) {
    const int s = pass == 0 ? 1 : -1;
    for (int zi = 0; zi < grid.dims[2]; ++zi) {
      const int z = pass == 0 ? zi : grid.dims[2] - 1 - zi;
      for (int yi = 0; yi < grid.dims[1]; ++yi) {
        const int y = pass == 0 ? yi : grid.dims[1] - 1 - yi;
        for (int xi = 0; xi < grid.dims[0]; ++xi) {
          const int x = pass == 0 ? xi : grid.dims[0] - 1 - xi;
          const size_t i = grid.Index(x, y, z);
          if (depth[i] == 0) continue;
          int d = depth[i];
          const int coords[3] = {x, y, z};
          for (int axis = 0; axis < 3; ++axis) {
            const int c = coords[axis] - s;
            if (c < 0 || c >= grid.dims[axis]) {
              d = std::min(d, 1);
              continue;
            }
            const size_t j = s > 0 ? i - grid.Stride(axis) : i + grid.Stride(axis);
            d = std::min(d, int(depth[j]) + 1);
          }
          depth[i] = uint16_t(d);
        }
      }
    }
  }
  // Of the deepest voxels (a box room has a whole slab of them), the one
  // nearest their centroid.
  const uint16_t most = *std::max_element(depth.begin(), depth.end());
  auto center_of = [&](size_t i) {
    const std::array<int, 3> coords = grid.Coords(i);
    std::array<double, 3> c{};
    for (int axis = 0; axis < 3; ++axis) c[axis] = min_[axis] + (double(coords[axis]) + 0.5) * voxel;
    return c;
  };
  std::array<double, 3> mean{};
  size_t deepest_count = 0;
  for (size_t i = 0; i < depth.size(); ++i) {
    if (depth[i] != most) continue;
    const std::array<double, 3> c = center_of(i);
    for (int axis = 0; axis < 3; ++axis) mean[axis] += c[axis];
    ++deepest_count;
  }
  for (double& m : mean) m /= double(deepest_count);
  double nearest = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < depth.size(); ++i) {
    if (depth[i] != most) continue;
    const std::array<double, 3> c = center_of(i);
    const double d2 = (c[0] - mean[0]) * (c[0] - mean[0]) + (c[1] - mean[1]) * (c[1] - mean[1]) +
                      (c[2] - mean[2]) * (c[2] - mean[2]);
    if (d2 < nearest) nearest = d2, deepest_ = c;
  }

  // The space reaches back to the scan: from the parts, every voxel without
  // a point reachable without entering the outside grown back by the gap
  // and a voxel (which fills an opening's width again, from outside), nor
  // crossing a voxel with a point. So it fills the room up to its walls and
  // furniture, also where they stand closer than 2 * gap_m, but not a closed
  // object's inside (a table's) nor the outside through a door.
  std::vector<uint8_t> reach(cells.size(), 0);
  for (size_t i = 0; i < cells.size(); ++i) reach[i] = cells[i] == kOutside ? 1 : 0;
  Grow(grid, outside_radius + 1, 1, reach);
  std::vector<uint32_t> queue;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i] == kEnclosed) {
      reach[i] = 2;
      queue.push_back(uint32_t(i));
    } else if (reach[i] == 0 && scanned[i] != kFree) {
      reach[i] = 1;  // a point's voxel: a wall
    }
  }
  Fill(grid, 0, 2, queue, reach);
  inside_.resize(cells.size());
  for (size_t i = 0; i < cells.size(); ++i) inside_[i] = reach[i] == 2;
}

Expected<EnclosedSpace> EnclosedSpace::Find(const PointCloud& cloud, const EnclosureOptions& options) {
  EnclosedSpace space;
  PB_ASSIGN_OR_RETURN(Voxels voxels, Prepare(cloud, options, options.gap_m, space.min_, space.voxel_m_));
  const Grid& grid = voxels.grid;
  std::vector<uint8_t>& cells = voxels.cells;
  space.dims_ = grid.dims;

  // The outside: free voxels the border reaches.
  std::vector<uint32_t> queue;
  for (int z = 0; z < grid.dims[2]; ++z) {
    for (int y = 0; y < grid.dims[1]; ++y) {
      for (int x = 0; x < grid.dims[0]; ++x) {
        const bool border = x == 0 || y == 0 || z == 0 || x == grid.dims[0] - 1 ||
                            y == grid.dims[1] - 1 || z == grid.dims[2] - 1;
        const size_t i = grid.Index(x, y, z);
        if (border && cells[i] == kFree) {
          cells[i] = kOutside;
          queue.push_back(uint32_t(i));
        }
      }
    }
  }
  Fill(grid, kFree, kOutside, queue, cells);

  // The enclosed parts, each kept if large enough.
  const size_t enclosed = KeepLargeParts(grid, space.voxel_m_, options.min_volume_m3, cells,
                                         [](const std::vector<uint32_t>&) { return true; });
  space.volume_m3_ = double(enclosed) * space.voxel_m_ * space.voxel_m_ * space.voxel_m_;
  if (enclosed > 0) space.Finish(cells, voxels.scanned, voxels.radius);
  return space;
}

Expected<EnclosedSpace> EnclosedSpace::FindOpen(const PointCloud& cloud, const EnclosureOptions& options) {
  EnclosedSpace space;
  space.open_ = true;
  PB_ASSIGN_OR_RETURN(Voxels voxels, Prepare(cloud, options, options.open_gap_m, space.min_, space.voxel_m_));
  const Grid& grid = voxels.grid;
  std::vector<uint8_t>& cells = voxels.cells;
  space.dims_ = grid.dims;

  // Free voxels from which too many lines of sight leave the scan are
  // outside; the others, surrounded, are candidates.
  const LinesOfSight lines = LinesOfSightMeetingTheScan(grid, cells);
  const int least = int(std::ceil(options.min_surrounded * 26 - 1e-9));
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i] == kFree && lines.meeting[i] < least) cells[i] = kOutside;
  }
  // A cup is an object's inside: along one axis the lines of sight leave
  // from most of it (through the unscanned underside it rests on) and the
  // other way from hardly any. A room's door lets few out; a corridor's ends
  // let most out both ways.
  auto not_a_cup = [&](const std::vector<uint32_t>& part) {
    std::array<size_t, 6> leaving{};
    for (uint32_t i : part) {
      for (int bit = 0; bit < 6; ++bit) leaving[bit] += (lines.leaving[i] >> bit) & 1u;
    }
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        const double out = double(leaving[2 * axis + side]) / double(part.size());
        const double back = double(leaving[2 * axis + 1 - side]) / double(part.size());
        if (out >= 0.5 && back <= 0.1) return false;
      }
    }
    return true;
  };
  const size_t enclosed = KeepLargeParts(grid, space.voxel_m_, options.min_open_volume_m3, cells, not_a_cup);
  space.volume_m3_ = double(enclosed) * space.voxel_m_ * space.voxel_m_ * space.voxel_m_;
  if (enclosed > 0) space.Finish(cells, voxels.scanned, voxels.radius);
  return space;
}

bool EnclosedSpace::Contains(const float p[3]) const {
  if (inside_.empty()) return false;
  int c[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double f = std::floor((double(p[axis]) - min_[axis]) / voxel_m_);
    if (!(f >= 0 && f < dims_[axis])) return false;
    c[axis] = int(f);
  }
  return inside_[Grid{dims_}.Index(c[0], c[1], c[2])] != 0;
}

}  // namespace pb
