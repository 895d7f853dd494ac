#pragma once
/// Caustics by ray tracing: collimated light passes through a transparent
/// slab — flat bottom at z = 0, top a height field z = h(x, y) > 0 over a
/// rectangle centred on the origin — refracting at every surface it crosses
/// (vector Snell's law, total internal reflection followed, Fresnel losses
/// optional), and lands on a receiver plane z = -distance below the slab.
/// Or the slab is a mirror (CausticSetup::mirror): every face reflects, and
/// the light lands on a receiver plane z = +distance above the bottom.
/// The output is the irradiance image on the receiver, in units of the
/// incident irradiance (a flat slab under normal light gives 1 everywhere it
/// covers).
///
/// The slab is one closed triangle mesh traced with Embree; the scene is
/// built once, and set_heights only moves the top vertices and refits the
/// BVH. Rays are stratified over the slab's footprint, one per cell, jittered
/// by a hash of the cell index: the same heights give the same image, bit for
/// bit, for any thread count (rays are traced in parallel, splatted in order).

#include <array>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace spec2fab {

struct CausticSetup {
  double width_mm = 50, depth_mm = 50;  ///< slab footprint along x and y, centred on the origin
  int vertices_x = 61, vertices_y = 61; ///< top height-field grid (corners included)
  double refractive_index = 1.5;
  /// The slab's faces reflect instead (a print coated as a mirror, the law
  /// of reflection at every face met): the receiver is the plane z =
  /// +receiver_distance_mm above the bottom, facing down. Light straight
  /// down would pass through it first; tilt light_direction and centre the
  /// receiver where the light goes (receiver_centre_mm).
  bool mirror = false;
  Eigen::Vector3d light_direction{0, 0, -1};  ///< direction the light travels (normalised on use)
  /// A point light (a bare LED) at light_position_mm instead — x, y from the
  /// footprint's centre, z above the bottom, above the top — radiating
  /// evenly in all directions with the intensity that gives unit irradiance
  /// across the beam at the distance z (under it, at the bottom's plane).
  bool point_light = false;
  Eigen::Vector3d light_position_mm{0, 0, 1000};
  double receiver_distance_mm = 100;          ///< receiver plane z = -distance
  double receiver_width_mm = 50, receiver_depth_mm = 50;
  Eigen::Vector2d receiver_centre_mm{0, 0};
  int image_width = 240, image_height = 240;
  /// The image as seen from the receiver's far side, looking back at the
  /// slab (columns_towards_minus_x: for a lens its columns run towards −x,
  /// rows still from +y; seen from the slab's side, as by default, a
  /// mirror's receiver above is looked up at, so its columns run towards −x
  /// unless this is set). Where the
  /// tracer's frame is the print's mirrored (caustics + texture: z = cut − w),
  /// this is the caustic as a viewer facing the wall sees it.
  bool image_from_behind = false;
  int rays_x = 480, rays_y = 480;  ///< source samples over the footprint
  bool jitter = true;              ///< jitter each sample within its stratum
  unsigned seed = 1;
  bool fresnel = false;            ///< weight transmissions by unpolarised Fresnel
  /// Light only through the disc (an ellipse on a rectangular footprint)
  /// inscribed in the footprint, as behind a round stop; false: all of it.
  bool disc_aperture = false;
  int max_segments = 16;           ///< segments traced per ray before it counts as lost
  /// How render() forms the image (caustic_triangles.cpp for the last two):
  /// - `rays` traces the stratified rays with Embree and splats them (any
  ///   surface, walls, total internal reflection, the exit filter);
  /// - `facets` sends each flat top triangle's beam through the flat bottom
  ///   as one parallel pencil and spreads its flux over the exact area it
  ///   lights: no sampling noise, exact for the piecewise-linear top (each
  ///   facet casts a copy of itself; concentration comes from overlaps);
  /// - `smooth` refracts at every vertex with the surface's normal there
  ///   (central differences of the heights) and spreads each triangle's
  ///   flux over the triangle its corners land on: the caustic of the smooth
  ///   surface the vertices sample, continuous in the heights, no noise.
  /// The two leave out side walls, shadowing and an exit filter.
  enum class Estimator { rays, facets, smooth };
  Estimator estimator = Estimator::rays;
  /// A filter printed on the flat bottom face (a texture): light leaving the
  /// slab there keeps this fraction of its power, per cell of an
  /// exit_cells[0] × exit_cells[1] grid over the footprint (row by row from
  /// the lowest y, x fastest). Empty: nothing absorbs.
  std::vector<double> exit_transmittance;
  std::array<int, 2> exit_cells{0, 0};

  /// Throws InputError naming the first inconsistent field.
  void validate() const;
  /// Every field, as a RunCache key's part (a field added here goes there too).
  std::string cache_key() const;
};

/// Lateral position of top vertex (i, j) of the setup's grid (i along x),
/// the footprint centred on the origin.
inline Eigen::Vector2d slab_vertex_xy(const CausticSetup& s, int i, int j) {
  return {s.width_mm * (static_cast<double>(i) / (s.vertices_x - 1) - 0.5),
          s.depth_mm * (static_cast<double>(j) / (s.vertices_y - 1) - 0.5)};
}

/// Where the emitted light went, in units of incident irradiance × mm².
struct CausticFlux {
  double emitted = 0;
  double received = 0;     ///< deposited on the image
  double missed = 0;       ///< reached the receiver plane outside the image
  double returned = 0;     ///< left the slab travelling away from the receiver (e.g. TIR back out)
  double reflected = 0;    ///< Fresnel reflections, when enabled
  double absorbed = 0;     ///< taken by the exit filter (CausticSetup::exit_transmittance)
  double lost = 0;         ///< still bouncing after max_segments
};

/// Unpolarised Fresnel reflectance for the cosines of incidence and
/// transmission going from index eta_i to eta_t.
inline double fresnel_reflectance(double eta_i, double eta_t, double cos_i, double cos_t) {
  const double rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
  const double rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

/// The direction (unit) light travels at point p: the collimated beam's, or
/// away from the point light.
template <class T>
Eigen::Matrix<T, 3, 1> light_towards(const CausticSetup& s, const Eigen::Matrix<T, 3, 1>& p) {
  using std::sqrt;
  if (!s.point_light) return s.light_direction.normalized().cast<T>();
  const Eigen::Matrix<T, 3, 1> away = p - s.light_position_mm.cast<T>();
  return away / sqrt(away.dot(away));
}

/// The light crossing a small flat patch at c whose area vector (normal ×
/// area) faces the light: the beam's unit irradiance times the projected
/// area, or for the point light its intensity times the solid angle the
/// patch subtends (to second order in its size over its distance).
template <class T>
T light_through(const CausticSetup& s, const Eigen::Matrix<T, 3, 1>& c, const Eigen::Matrix<T, 3, 1>& area) {
  using std::sqrt;
  if (!s.point_light) return -area.dot(s.light_direction.normalized().cast<T>());
  const Eigen::Matrix<T, 3, 1> to_light = s.light_position_mm.cast<T>() - c;
  const T r2 = to_light.dot(to_light);
  return T(s.light_position_mm.z() * s.light_position_mm.z()) * area.dot(to_light) / (r2 * sqrt(r2));
}

/// Collimated light along `light` (unit) through a top facet of outward
/// unit normal `normal`, into the slab and out of its flat bottom: the
/// directions inside and out, and the cosines Fresnel's law needs. The
/// refractions the tracer performs, for any scalar, so that a forward-mode
/// derivative type carries derivatives through them.
template <class T>
struct SlabPassage {
  Eigen::Matrix<T, 3, 1> inside, out;
  T cos_i, cos_t, cos_b, cos_out;  ///< top: incidence, transmission; bottom: incidence, transmission
};

/// The passage, or false when the light cannot make it (it would leave
/// the top upwards, or is totally reflected at the bottom).
template <class T, class Light>
bool pass_through_slab(const Light& light, const Eigen::Matrix<T, 3, 1>& normal, double eta,
                       SlabPassage<T>& pass) {
  using std::sqrt;
  pass.cos_i = -(light.x() * normal.x() + light.y() * normal.y() + light.z() * normal.z());
  const T ratio(1.0 / eta);
  pass.cos_t = sqrt(T(1.0) - ratio * ratio * (T(1.0) - pass.cos_i * pass.cos_i));
  pass.inside = ratio * light.template cast<T>() + (ratio * pass.cos_i - pass.cos_t) * normal;
  if (!(pass.inside.z() < T(0.0))) return false;
  // Out through the bottom, whose normal facing the light is +z.
  pass.cos_b = -pass.inside.z();
  const T sin2_out = T(eta * eta) * (T(1.0) - pass.cos_b * pass.cos_b);
  if (!(sin2_out < T(1.0))) return false;
  pass.cos_out = sqrt(T(1.0) - sin2_out);
  pass.out = T(eta) * pass.inside;
  pass.out.z() += T(eta) * pass.cos_b - pass.cos_out;
  return true;
}

/// Where light that entered the top at `p` and passed as `pass` lands on
/// the receiver plane z = receiver_z.
template <class T>
Eigen::Matrix<T, 2, 1> slab_landing(const Eigen::Matrix<T, 3, 1>& p, const SlabPassage<T>& pass, double receiver_z) {
  const Eigen::Matrix<T, 3, 1> bottom = p - (p.z() / pass.inside.z()) * pass.inside;
  return (bottom + ((T(receiver_z) - bottom.z()) / pass.out.z()) * pass.out).template head<2>();
}

/// Light along `light` (unit) reflected by a mirror face of outward unit
/// normal `normal`: the direction out, and the cosine of incidence (in
/// `pass.out` and `pass.cos_i`; the rest of `pass` is not used). False when
/// the light meets the face from behind or is sent downwards.
template <class T, class Light>
bool reflect_off_top(const Light& light, const Eigen::Matrix<T, 3, 1>& normal, SlabPassage<T>& pass) {
  pass.cos_i = -(light.x() * normal.x() + light.y() * normal.y() + light.z() * normal.z());
  if (!(pass.cos_i > T(0.0))) return false;
  pass.out = light.template cast<T>() + T(2.0) * pass.cos_i * normal;
  return pass.out.z() > T(0.0);
}

/// Where light along `light` (unit) that meets the top at `at`, outward unit
/// normal `normal` there, lands on the receiver (lateral mm): through the
/// slab to z = −distance, or off the mirror to z = +distance. False when it
/// cannot get there (pass_through_slab, reflect_off_top); `pass` gets the
/// directions and the cosines.
template <class T, class Light>
bool top_landing(const CausticSetup& s, const Light& light, const Eigen::Matrix<T, 3, 1>& normal,
                 const Eigen::Matrix<T, 3, 1>& at, SlabPassage<T>& pass, Eigen::Matrix<T, 2, 1>& landing) {
  if (s.mirror) {
    if (!reflect_off_top(light, normal, pass)) return false;
    landing = (at + ((T(s.receiver_distance_mm) - at.z()) / pass.out.z()) * pass.out).template head<2>();
    return true;
  }
  if (!pass_through_slab(light, normal, s.refractive_index, pass)) return false;
  landing = slab_landing(at, pass, -s.receiver_distance_mm);
  return true;
}

/// Where a ray from `origin` along `direction` (unit) meeting the top
/// triangle with lateral corners `xy` (counter-clockwise seen from above) and
/// heights `h` lands on the setup's receiver (top_landing). NaN when it
/// cannot.
template <class T>
Eigen::Matrix<T, 2, 1> top_receiver_point(const CausticSetup& s, const Eigen::Vector3d& origin,
                                          const Eigen::Vector3d& direction, const Eigen::Vector2d xy[3], const T h[3]) {
  using std::sqrt;
  using V = Eigen::Matrix<T, 3, 1>;
  const V p0(T(xy[0].x()), T(xy[0].y()), h[0]), p1(T(xy[1].x()), T(xy[1].y()), h[1]),
      p2(T(xy[2].x()), T(xy[2].y()), h[2]);
  V n = (p1 - p0).cross(p2 - p0);
  n /= sqrt(n.dot(n));
  const V o = origin.cast<T>(), d = direction.cast<T>();
  const V hit = o + (n.dot(p0 - o) / n.dot(d)) * d;
  SlabPassage<T> pass;
  Eigen::Matrix<T, 2, 1> landing;
  if (!top_landing(s, direction, n, hit, pass, landing))
    return Eigen::Matrix<T, 2, 1>::Constant(T(std::numeric_limits<double>::quiet_NaN()));
  return landing;
}

/// Whether the image's columns run towards −x: seen from the side of the
/// receiver the slab is not on (image_from_behind) for a lens, and from the
/// slab's side, looking up, for a mirror, unless image_from_behind.
inline bool columns_towards_minus_x(const CausticSetup& s) { return s.image_from_behind != s.mirror; }

/// Pixel coordinates (u right, v down from the image's top edge; pixel
/// (c, r) covers [c, c+1] × [r, r+1]) of receiver point `xy`.
template <class T>
Eigen::Matrix<T, 2, 1> receiver_pixel(const CausticSetup& s, const Eigen::Matrix<T, 2, 1>& xy) {
  const double half = 0.5 * s.receiver_width_mm, top = s.receiver_centre_mm.y() + 0.5 * s.receiver_depth_mm;
  const T across = columns_towards_minus_x(s) ? T(s.receiver_centre_mm.x() + half) - xy.x()
                                       : xy.x() - T(s.receiver_centre_mm.x() - half);
  return {across * (s.image_width / s.receiver_width_mm), (top - xy.y()) * (s.image_height / s.receiver_depth_mm)};
}


class CausticTracer {
 public:
  explicit CausticTracer(const CausticSetup& setup);
  /// Traces a given closed, outward-oriented mesh instead (an exported STL,
  /// moved so that the slab's footprint is centred on the origin): no height
  /// field, so set_heights and pull_back do not apply, nor the smooth
  /// estimator; the facet estimator takes the facets facing up as the top.
  CausticTracer(const CausticSetup& setup, std::vector<Eigen::Vector3d> vertices,
                std::vector<Eigen::Vector3i> triangles);
  ~CausticTracer();
  CausticTracer(const CausticTracer&) = delete;
  CausticTracer& operator=(const CausticTracer&) = delete;

  const CausticSetup& setup() const { return setup_; }
  /// Lateral position of top vertex (i, j), i along x.
  Eigen::Vector2d vertex_xy(int i, int j) const { return slab_vertex_xy(setup_, i, j); }

  /// Replaces the exit filter (CausticSetup::exit_transmittance); validated
  /// as the setup is.
  void set_exit_transmittance(std::array<int, 2> cells, std::vector<double> transmittance);

  /// Heights (mm, > 0) of the top vertices, row by row (x fastest).
  void set_heights(std::span<const double> heights_mm);
  std::span<const double> heights() const { return heights_; }

  /// The image the current surface casts, into `irradiance` (image_width ×
  /// image_height, row 0 at +y), by the setup's estimator.
  CausticFlux render(std::span<double> irradiance);

  /// Reverse mode: given ∂E/∂pixel for the image the last render made,
  /// writes ∂E/∂height of every top vertex into `d_heights` (heights()
  /// order). With the triangle estimator: exact, every pixel's share of
  /// every triangle differentiated through the clipping. With rays: exact for that render's rays as traced: a ray's receiver point
  /// moves with the heights of the top triangle it entered (its plane and
  /// normal), bilinear splat weights move with the point. Rays that did more
  /// than enter the top and leave by the flat bottom (side walls, total
  /// internal reflection) are held fixed, as is Fresnel transmittance, and
  /// so is the plane tilted light starts from (tied to the highest vertex).
  void pull_back(std::span<const double> d_irradiance, std::span<double> d_heights);

  /// The slab as a closed, outward-oriented triangle mesh (vertices in mm):
  /// what is traced.
  void mesh(std::vector<Eigen::Vector3d>& vertices, std::vector<Eigen::Vector3i>& triangles) const;

 private:
  struct Scene;
  struct RayResult {
    double x = 0, y = 0, power = 0, reflected = 0, absorbed = 0;
    int fate = 0;
    int entry = -1;  ///< top triangle entered, when the path was top → bottom → receiver
  };
  Eigen::Vector3d ray_origin(int ray) const;
  /// The exit filter's transmittance where a ray leaves the bottom at (x, y).
  double exit_transmittance_at(double x, double y) const;
  /// Traces rays [begin, end) together: each segment of all rays still in
  /// flight is one coherent Embree stream query.
  void trace_block(int begin, int end);
  /// Ray `ray`'s start above the slab and the light it carries (none when
  /// the disc aperture stops it: then false).
  bool launch(int ray, Eigen::Vector3d& origin, Eigen::Vector3d& direction);
  /// Segment `segment` of a ray from `origin` along `direction`: what it met
  /// (`hit`: triangle `triangle` at distance `t`, else the receiver or
  /// nothing) and where it goes on; false when it is done.
  bool follow(bool hit, unsigned triangle, double t, int segment, Eigen::Vector3d& origin,
              Eigen::Vector3d& direction, RayResult& result) const;
  CausticFlux render_rays(std::span<double> irradiance);
  void pull_back_rays(std::span<const double> d_irradiance, std::span<double> d_heights);
  CausticFlux render_triangles(std::span<double> irradiance);
  void pull_back_triangles(std::span<const double> d_irradiance, std::span<double> d_heights);
  /// Smooth estimator: where each top vertex's light lands (pixel
  /// coordinates; NaN when it cannot leave by the bottom).
  void land_vertices();
  void pull_back_smooth(std::span<const double> d_irradiance, std::span<double> d_heights);
  /// The vertex grid neighbours the smooth estimator's normal at `vertex`
  /// reads: itself, then along x (low, high), then along y (low, high).
  std::array<int, 5> normal_stencil(int vertex) const;
  void build_scene();
  void update_vertex_buffer();
  /// Receiver point (u, v) in pixels of a received ray (the splat's frame).
  Eigen::Vector2d pixel_coordinates(const RayResult& ray) const;
  double pixels_per_mm2() const;
  /// The bilinear splat at (u, v): visit(pixel, weight_u, weight_v, sign_u,
  /// sign_v) for each in-image corner; its weight is weight_u · weight_v and
  /// ∂weight/∂u = sign_u · weight_v (∂/∂v likewise). False, visiting
  /// nothing, when no corner is on the image. Render and pull_back share it,
  /// so the derivative is of the splat actually drawn.
  template <class Visit>
  bool for_each_splat_corner(const Eigen::Vector2d& uv, Visit&& visit) const;

  CausticSetup setup_;
  std::vector<double> heights_;
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Eigen::Vector3i> triangles_;
  std::vector<Eigen::Vector3d> normals_;  ///< outward unit normal per triangle
  std::vector<RayResult> results_;
  std::vector<Eigen::Vector3d> ray_gradients_;  ///< ∂E/∂h of each ray's entry triangle's vertices
  /// The triangle estimator's deposits (pixel, irradiance), one list per
  /// fixed block of triangles, merged in block order (thread-independent sums).
  std::vector<std::vector<std::pair<unsigned, double>>> triangle_deposits_;
  std::vector<CausticFlux> triangle_fluxes_;
  std::vector<Eigen::Vector3d> triangle_gradients_;
  std::vector<Eigen::Vector2d> landing_;                    ///< smooth: each top vertex's landing point
  std::vector<Eigen::Matrix<double, 6, 1>> corner_gradients_;  ///< smooth: ∂E/∂ each triangle's landing points
  std::vector<Eigen::Vector3d> light_gradients_;  ///< smooth, point light: ∂E/∂ each triangle's heights through its share of the light
  std::vector<Eigen::Vector2d> landing_gradients_;          ///< smooth: ∂E/∂ each vertex's landing point
  std::vector<Eigen::Matrix<double, 5, 1>> vertex_gradients_;  ///< smooth: ∂E/∂ each vertex's stencil heights
  int top_triangles_ = 0;
  std::unique_ptr<Scene> scene_;
  double top_z_ = 0;
  double start_z_ = 0;  ///< rays start here, just above the highest point
};

}  // namespace spec2fab
