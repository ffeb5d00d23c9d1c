#include "mesh_tools.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <utility>

#include "far/scenes/scenes.h"

namespace far::scenes {

Mesh RefineMesh(const Mesh& mesh, int n) {
  n = std::max(1, n);
  if (n == 1) return mesh;
  Mesh out;
  out.p_MV = mesh.p_MV;
  const auto num = static_cast<double>(n);
  // The n - 1 inner points of an edge are made once, by the first triangle that uses the edge,
  // in the direction from its smaller to its larger vertex index; the other triangle reuses
  // them, so the refined mesh is welded (a closed mesh stays closed).
  std::unordered_map<uint64_t, uint32_t> edge_points;
  edge_points.reserve(mesh.triangles.size() * 3 / 2);
  const auto edge_point = [&](uint32_t a, uint32_t b, int k) -> uint32_t {
    // Point k of n along a -> b, 0 < k < n.
    const uint32_t lo = std::min(a, b), hi = std::max(a, b);
    const int k_lo = a == lo ? k : n - k;
    const uint64_t key = (static_cast<uint64_t>(lo) << 32) | hi;
    auto [it, inserted] = edge_points.try_emplace(key, static_cast<uint32_t>(out.p_MV.size()));
    if (inserted) {
      for (int i = 1; i < n; ++i)
        out.p_MV.push_back(mesh.p_MV[lo] + (i / num) * (mesh.p_MV[hi] - mesh.p_MV[lo]));
    }
    return it->second + static_cast<uint32_t>(k_lo - 1);
  };
  std::vector<uint32_t> lattice(static_cast<size_t>((n + 1) * (n + 2) / 2));
  out.triangles.reserve(mesh.triangles.size() * static_cast<size_t>(n * n));
  for (const TriangleIndices& t : mesh.triangles) {
    // Lattice point (i, j), i + j <= n: a + i/n (b - a) + j/n (c - a).
    const auto at = [n](int i, int j) {
      return static_cast<size_t>(j * (n + 1) - j * (j - 1) / 2 + i);
    };
    const Eigen::Vector3d& a = mesh.p_MV[t[0]];
    const Eigen::Vector3d e1 = (mesh.p_MV[t[1]] - a) / num, e2 = (mesh.p_MV[t[2]] - a) / num;
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i + j <= n; ++i) {
        uint32_t index;
        if (i == 0 && j == 0) {
          index = t[0];
        } else if (i == n) {
          index = t[1];
        } else if (j == n) {
          index = t[2];
        } else if (j == 0) {
          index = edge_point(t[0], t[1], i);
        } else if (i == 0) {
          index = edge_point(t[0], t[2], j);
        } else if (i + j == n) {
          index = edge_point(t[1], t[2], j);
        } else {
          index = static_cast<uint32_t>(out.p_MV.size());
          out.p_MV.push_back(a + i * e1 + j * e2);
        }
        lattice[at(i, j)] = index;
      }
    }
    // Scaled copies of (a, b, c), "up" and "down", keep the parent's orientation.
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        out.triangles.push_back({lattice[at(i, j)], lattice[at(i + 1, j)], lattice[at(i, j + 1)]});
        if (i + j + 1 < n) {
          out.triangles.push_back(
              {lattice[at(i + 1, j)], lattice[at(i + 1, j + 1)], lattice[at(i, j + 1)]});
        }
      }
    }
  }
  return out;
}

}  // namespace far::scenes

namespace far::scenes::internal {

int TubeTriangles(int sides, int segments) { return 2 * sides * segments + 2 * sides; }

void AppendTube(Mesh* mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r_a,
                double r_b, int sides, int segments) {
  const Eigen::Vector3d axis = (b - a).normalized();
  const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.cross(u);
  const auto base = static_cast<uint32_t>(mesh->p_MV.size());
  const auto n = static_cast<uint32_t>(sides);
  for (int k = 0; k <= segments; ++k) {
    const double s = static_cast<double>(k) / segments;
    const Eigen::Vector3d center = a + s * (b - a);
    const double radius = r_a + s * (r_b - r_a);
    for (int i = 0; i < sides; ++i) {
      const double phi = 2 * std::numbers::pi * i / sides;
      mesh->p_MV.push_back(center + radius * (std::cos(phi) * u + std::sin(phi) * v));
    }
  }
  const auto ring = [&](int k, uint32_t i) {
    return base + static_cast<uint32_t>(k) * n + (i % n);
  };
  for (int k = 0; k < segments; ++k) {
    for (uint32_t i = 0; i < n; ++i) {
      mesh->triangles.push_back({ring(k, i), ring(k, i + 1), ring(k + 1, i + 1)});
      mesh->triangles.push_back({ring(k, i), ring(k + 1, i + 1), ring(k + 1, i)});
    }
  }
  const auto center_a = static_cast<uint32_t>(mesh->p_MV.size());
  mesh->p_MV.push_back(a);
  mesh->p_MV.push_back(b);
  for (uint32_t i = 0; i < n; ++i) {
    mesh->triangles.push_back({center_a, ring(0, i + 1), ring(0, i)});
    mesh->triangles.push_back({center_a + 1, ring(segments, i), ring(segments, i + 1)});
  }
}

std::vector<TriangleIndices> GridTriangles(int cells) {
  std::vector<TriangleIndices> triangles;
  const auto index = [&](int i, int j) { return static_cast<uint32_t>(i * (cells + 1) + j); };
  for (int i = 0; i < cells; ++i) {
    for (int j = 0; j < cells; ++j) {
      triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
      triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
    }
  }
  return triangles;
}

Mesh LatheMesh(std::span<const Eigen::Vector2d> radius_z, double z_bottom, double z_top,
               int slices) {
  Mesh mesh;
  const auto rings = static_cast<int>(radius_z.size());
  mesh.p_MV.reserve(static_cast<size_t>(rings * slices + 2));
  mesh.p_MV.emplace_back(0, 0, z_bottom);
  for (const Eigen::Vector2d& rz : radius_z) {
    for (int j = 0; j < slices; ++j) {
      const double phi = 2 * std::numbers::pi * j / slices;
      mesh.p_MV.emplace_back(rz.x() * std::cos(phi), rz.x() * std::sin(phi), rz.y());
    }
  }
  mesh.p_MV.emplace_back(0, 0, z_top);
  const auto ring = [&](int i, int j) {
    return static_cast<uint32_t>(1 + i * slices + (j % slices));
  };
  const auto top = static_cast<uint32_t>(mesh.p_MV.size() - 1);
  mesh.triangles.reserve(static_cast<size_t>(2 * slices * rings));
  for (int j = 0; j < slices; ++j) {
    mesh.triangles.push_back({0, ring(0, j + 1), ring(0, j)});
    for (int i = 0; i + 1 < rings; ++i) {
      mesh.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)});
      mesh.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)});
    }
    mesh.triangles.push_back({ring(rings - 1, j), ring(rings - 1, j + 1), top});
  }
  return mesh;
}

Mesh HeightField::ToMesh() const {
  Mesh mesh;
  mesh.p_MV.reserve(z_.size());
  for (int j = 0; j <= cells_y_; ++j) {
    for (int i = 0; i <= cells_x_; ++i) mesh.p_MV.emplace_back(X(i), Y(j), z_[Index(i, j)]);
  }
  mesh.triangles.reserve(static_cast<size_t>(2 * cells_x_ * cells_y_));
  for (int j = 0; j < cells_y_; ++j) {
    for (int i = 0; i < cells_x_; ++i) {
      const auto v00 = static_cast<uint32_t>(Index(i, j)),
                 v10 = static_cast<uint32_t>(Index(i + 1, j));
      const auto v01 = static_cast<uint32_t>(Index(i, j + 1));
      const auto v11 = static_cast<uint32_t>(Index(i + 1, j + 1));
      mesh.triangles.push_back({v00, v10, v11});
      mesh.triangles.push_back({v00, v11, v01});
    }
  }
  return mesh;
}

double HeightField::Height(double x, double y) const {
  const double fx = std::clamp((x - min_.x()) / step_.x(), 0.0, static_cast<double>(cells_x_));
  const double fy = std::clamp((y - min_.y()) / step_.y(), 0.0, static_cast<double>(cells_y_));
  const int i = std::min(static_cast<int>(fx), cells_x_ - 1);
  const int j = std::min(static_cast<int>(fy), cells_y_ - 1);
  const double u = fx - i, v = fy - j;
  const double z00 = z_[Index(i, j)], z10 = z_[Index(i + 1, j)];
  const double z01 = z_[Index(i, j + 1)], z11 = z_[Index(i + 1, j + 1)];
  // The cell's two triangles share the diagonal u == v.
  if (u >= v) return z00 + u * (z10 - z00) + v * (z11 - z10);
  return z00 + v * (z01 - z00) + u * (z11 - z01);
}

Pose RestOn(const HeightField& ground, std::span<const Eigen::Vector3d> p_OV,
            const Eigen::Quaterniond& rotation, const Eigen::Vector2d& xy, double depth) {
  const Eigen::Matrix3d R = rotation.normalized().toRotationMatrix();
  double lowest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& p : p_OV) {
    const Eigen::Vector3d q = R * p;
    lowest = std::min(lowest, q.z() - ground.Height(xy.x() + q.x(), xy.y() + q.y()));
  }
  return MakePose(Eigen::Vector3d(xy.x(), xy.y(), -depth - lowest), rotation);
}

std::vector<Fragment> Fracture(const Mesh& mesh, int num_pieces, const Eigen::Vector3d& core,
                               std::mt19937_64* rng) {
  const int num_triangles = mesh.num_triangles();
  num_pieces = std::clamp(num_pieces, 1, num_triangles);
  std::vector<Eigen::Vector3d> centroids(static_cast<size_t>(num_triangles));
  for (size_t t = 0; t < centroids.size(); ++t) {
    const TriangleIndices& v = mesh.triangles[t];
    centroids[t] = (mesh.p_MV[v[0]] + mesh.p_MV[v[1]] + mesh.p_MV[v[2]]) / 3;
  }
  // Distinct seed triangles; each is nearest to itself, so no cell is empty.
  std::vector<int> seeds;
  std::uniform_int_distribution<int> pick(0, num_triangles - 1);
  while (static_cast<int>(seeds.size()) < num_pieces) {
    const int t = pick(*rng);
    if (std::find(seeds.begin(), seeds.end(), t) == seeds.end()) seeds.push_back(t);
  }
  std::vector<int> cell(static_cast<size_t>(num_triangles));
  for (size_t t = 0; t < centroids.size(); ++t) {
    double best = std::numeric_limits<double>::infinity();
    for (int s = 0; s < num_pieces; ++s) {
      const double d = (centroids[t] - centroids[static_cast<size_t>(seeds[s])]).squaredNorm();
      if (d < best) best = d, cell[t] = s;
    }
  }
  // Directed edge -> triangle, to find each piece's boundary edges.
  const auto key = [](uint32_t a, uint32_t b) { return (static_cast<uint64_t>(a) << 32) | b; };
  std::unordered_map<uint64_t, uint32_t> edge_owner;
  edge_owner.reserve(static_cast<size_t>(num_triangles) * 3);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const TriangleIndices& v = mesh.triangles[t];
    for (int e = 0; e < 3; ++e)
      edge_owner.emplace(key(v[e], v[(e + 1) % 3]), static_cast<uint32_t>(t));
  }
  std::vector<Fragment> pieces(static_cast<size_t>(num_pieces));
  std::vector<uint32_t> local(mesh.p_MV.size());
  std::vector<int> local_of(mesh.p_MV.size(), -1);  // piece whose `local` entry is valid
  for (int s = 0; s < num_pieces; ++s) {
    Mesh& piece = pieces[static_cast<size_t>(s)].mesh;
    const auto vertex = [&](uint32_t v) {
      if (local_of[v] != s) {
        local_of[v] = s;
        local[v] = static_cast<uint32_t>(piece.p_MV.size());
        piece.p_MV.push_back(mesh.p_MV[v]);
      }
      return local[v];
    };
    std::vector<std::pair<uint32_t, uint32_t>> boundary;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      if (cell[t] != s) continue;
      const TriangleIndices& v = mesh.triangles[t];
      piece.triangles.push_back({vertex(v[0]), vertex(v[1]), vertex(v[2])});
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = v[e], b = v[(e + 1) % 3];
        const auto twin = edge_owner.find(key(b, a));
        if (twin == edge_owner.end() || cell[twin->second] != s) boundary.emplace_back(a, b);
      }
    }
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : piece.p_MV) centroid += p;
    centroid /= static_cast<double>(piece.p_MV.size());
    // The fan closes every boundary loop at once, however many loops the cell has.
    const auto apex = static_cast<uint32_t>(piece.p_MV.size());
    piece.p_MV.push_back(core + 0.35 * (centroid - core));
    for (const auto& [a, b] : boundary) piece.triangles.push_back({local[b], local[a], apex});
    for (Eigen::Vector3d& p : piece.p_MV) p -= centroid;
    pieces[static_cast<size_t>(s)].p_OF = centroid;
  }
  return pieces;
}

Eigen::Quaterniond RotationVector(const Eigen::Vector3d& angle_axis) {
  const double angle = angle_axis.norm();
  if (angle == 0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, angle_axis / angle));
}

Pose MakePose(const Eigen::Vector3d& translation, const Eigen::Quaterniond& rotation) {
  Pose pose;
  pose.translation = translation;
  pose.rotation = rotation.normalized();
  return pose;
}

std::pair<uint32_t, Mesh> VertexUpdate(uint32_t id, std::vector<Eigen::Vector3d> p_MV,
                                       const std::vector<TriangleIndices>& triangles) {
  Mesh mesh;
  mesh.p_MV = std::move(p_MV);
  mesh.triangles = triangles;
  return {id, std::move(mesh)};
}

}  // namespace far::scenes::internal
