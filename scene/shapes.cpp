#include "scene/shapes.hpp"

#include <numbers>

namespace scatter {
namespace {

constexpr double kPi = std::numbers::pi;

// Two unit vectors completing `axis` to a right-handed orthonormal frame.
void basis(const Vec3& axis, Vec3& u, Vec3& v) {
  Vec3 helper = std::abs(axis.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  u = normalize(cross(helper, axis));
  v = cross(axis, u);
}

Mesh sphere_mesh(const Shape& s, int detail) {
  // Latitude rings between the poles; the poles are single vertices so the mesh is watertight.
  int rings = std::max(4, detail / 2), cols = std::max(6, detail);
  Mesh m;
  m.positions.push_back(s.center + Vec3{0, s.radius, 0});
  for (int r = 1; r < rings; ++r) {
    double th = kPi * r / rings;
    for (int c = 0; c < cols; ++c) {
      double ph = 2 * kPi * c / cols;
      m.positions.push_back(s.center + s.radius * Vec3{std::sin(th) * std::cos(ph), std::cos(th),
                                                       -std::sin(th) * std::sin(ph)});
    }
  }
  m.positions.push_back(s.center - Vec3{0, s.radius, 0});
  auto ring = [&](int r, int c) { return uint32_t(1 + (r - 1) * cols + (c % cols)); };
  uint32_t south = static_cast<uint32_t>(m.positions.size() - 1);
  for (int c = 0; c < cols; ++c) {
    m.indices.insert(m.indices.end(), {0u, ring(1, c), ring(1, c + 1)});
    m.indices.insert(m.indices.end(), {south, ring(rings - 1, c + 1), ring(rings - 1, c)});
  }
  for (int r = 1; r < rings - 1; ++r)
    for (int c = 0; c < cols; ++c)
      m.indices.insert(m.indices.end(), {ring(r, c), ring(r + 1, c), ring(r + 1, c + 1), ring(r, c),
                                         ring(r + 1, c + 1), ring(r, c + 1)});
  m.normals.reserve(m.positions.size());
  for (const auto& p : m.positions) m.normals.push_back(normalize(p - s.center));
  m.orient_outwards();
  return m;
}

Mesh box_mesh(const Shape& s) {
  // Four vertices per face so that each face keeps its flat normal.
  Mesh m;
  Vec3 h = s.size * 0.5;
  for (int axis = 0; axis < 3; ++axis)
    for (int sign = -1; sign <= 1; sign += 2) {
      Vec3 n;
      n[axis] = sign;
      Vec3 u, v;
      u[(axis + 1) % 3] = 1;
      v[(axis + 2) % 3] = 1;
      if (sign < 0) std::swap(u, v);
      auto base = static_cast<uint32_t>(m.positions.size());
      for (auto [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
        Vec3 p = n + u * a + v * b;
        m.positions.push_back(s.center + p * h);
        m.normals.push_back(n);
      }
      m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
  return m;
}

Mesh torus_mesh(const Shape& s, int detail) {
  int rings = std::max(8, detail * 2), cols = std::max(6, detail / 2);
  Vec3 u, v;
  basis(s.axis, u, v);
  Mesh m;
  for (int r = 0; r < rings; ++r) {
    double ph = 2 * kPi * r / rings;
    Vec3 radial = u * std::cos(ph) + v * std::sin(ph);
    for (int c = 0; c < cols; ++c) {
      double th = 2 * kPi * c / cols;
      Vec3 n = radial * std::cos(th) + s.axis * std::sin(th);
      m.positions.push_back(s.center + radial * s.major_radius + n * s.minor_radius);
      m.normals.push_back(n);
    }
  }
  for (int r = 0; r < rings; ++r)
    for (int c = 0; c < cols; ++c) {
      uint32_t a = r * cols + c, b = r * cols + (c + 1) % cols;
      uint32_t d = ((r + 1) % rings) * cols + c, e = ((r + 1) % rings) * cols + (c + 1) % cols;
      m.indices.insert(m.indices.end(), {a, e, b, a, d, e});
    }
  m.orient_outwards();
  return m;
}

}  // namespace

bool Shape::inside(const Vec3& p) const {
  Vec3 d = p - center;
  switch (kind) {
    case Kind::Sphere:
      return dot(d, d) <= radius * radius;
    case Kind::Box:
      return std::abs(d.x) <= size.x / 2 && std::abs(d.y) <= size.y / 2 &&
             std::abs(d.z) <= size.z / 2;
    case Kind::Torus: {
      double h = dot(d, axis);
      double rho = length(d - axis * h) - major_radius;
      return rho * rho + h * h <= minor_radius * minor_radius;
    }
  }
  return false;
}

Aabb Shape::bounds() const {
  Vec3 h;
  switch (kind) {
    case Kind::Sphere:
      h = {radius, radius, radius};
      break;
    case Kind::Box:
      h = size * 0.5;
      break;
    case Kind::Torus: {
      double r = major_radius + minor_radius;
      h = {r, r, r};
      break;
    }
  }
  Aabb b;
  b.add(center - h);
  b.add(center + h);
  return b;
}

double Shape::volume() const {
  switch (kind) {
    case Kind::Sphere:
      return 4.0 / 3.0 * kPi * radius * radius * radius;
    case Kind::Box:
      return size.x * size.y * size.z;
    case Kind::Torus:
      return 2 * kPi * kPi * major_radius * minor_radius * minor_radius;
  }
  return 0;
}

Mesh Shape::tessellate(int detail) const {
  switch (kind) {
    case Kind::Sphere:
      return sphere_mesh(*this, detail);
    case Kind::Box:
      return box_mesh(*this);
    case Kind::Torus:
      return torus_mesh(*this, detail);
  }
  return {};
}

Shape Shape::parse(JsonObject& obj) {
  constexpr Range kLength{1e-6, 1e6};
  constexpr Range kCoord{-1e6, 1e6};
  Shape s;
  std::string kind = obj.choice("shape", {"sphere", "box", "torus"}, std::nullopt);
  s.center = obj.vec3("center", Vec3{}, kCoord);
  if (kind == "sphere") {
    s.kind = Kind::Sphere;
    s.radius = obj.number("radius", 1.0, kLength);
  } else if (kind == "box") {
    s.kind = Kind::Box;
    s.size = obj.vec3("size", Vec3{2, 2, 2}, kLength);
  } else {
    s.kind = Kind::Torus;
    s.major_radius = obj.number("major_radius", 0.6, kLength);
    s.minor_radius = obj.number("minor_radius", 0.25, kLength);
    if (s.minor_radius >= s.major_radius)
      throw ValidationError(obj.path("minor_radius"), "must be smaller than major_radius");
    Vec3 axis = obj.vec3("axis", Vec3{0, 1, 0}, kCoord);
    if (length(axis) < 1e-9) throw ValidationError(obj.path("axis"), "must not be zero");
    s.axis = normalize(axis);
  }
  return s;
}

}  // namespace scatter
