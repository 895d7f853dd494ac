#pragma once
/// What simulators produce and goals describe. Each observation type has a
/// name (`kType`); a tuner's simulator, metric and goal must agree on it —
/// at compile time when a translator is written in C++ (see parts.h), at load
/// time when assembled from JSON.
///
/// Every observation also exposes its numbers as one flat array, so that
/// generic machinery (error diffusion between tuners, CSV output) needs no
/// knowledge of the type, and writes itself to files (`spec2fab simulate`,
/// run previews): a new observation type says how in its own file, by
/// overriding write_files; there is no list of types to extend.

#include <array>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/radial_basis.h"

namespace spec2fab {

class Observation {
 public:
  virtual ~Observation() = default;
  virtual std::string_view type() const = 0;
  virtual std::span<const double> values() const = 0;
  virtual std::span<double> values() = 0;
  virtual std::unique_ptr<Observation> clone() const = 0;
  /// Writes the observation into `folder` in the format that fits it and
  /// returns the file names; by default its values as values.csv.
  virtual std::vector<std::string> write_files(const std::filesystem::path& folder) const;
};

template <class Derived>
class ObservationOf : public Observation {
 public:
  std::string_view type() const final { return Derived::kType; }
  std::unique_ptr<Observation> clone() const final {
    return std::make_unique<Derived>(static_cast<const Derived&>(*this));
  }
};

/// A raster image, row-major, `channels` interleaved values per pixel (linear).
struct ImageObservation final : ObservationOf<ImageObservation> {
  static constexpr std::string_view kType = "image";
  int width = 0, height = 0, channels = 1;
  std::vector<double> pixels;
  std::span<const double> values() const override { return pixels; }
  std::span<double> values() override { return pixels; }
  /// image.png (sRGB, 8 bit; scaled so the brightest is white when values exceed 1).
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

/// A radial diffuse reflectance profile R(r), RGB, as coefficients of an
/// orthonormal Fourier–Bessel basis on a disc (core/radial_basis.h): the
/// squared distance between two coefficient vectors is the area-integrated
/// squared difference of the profiles. samples() gives R(r) at the basis's radii.
struct RadialProfileObservation final : ObservationOf<RadialProfileObservation> {
  static constexpr std::string_view kType = "radial_profile";
  std::shared_ptr<const RadialBasis> basis;
  std::vector<double> coefficients;  ///< 3 per basis function (RGB interleaved)

  void reset(std::shared_ptr<const RadialBasis> b) {
    basis = std::move(b);
    coefficients.assign(3 * static_cast<size_t>(basis->size()), 0.0);
  }
  /// R(r_n) at basis->radii(), RGB interleaved.
  std::vector<double> samples() const {
    std::vector<double> out(coefficients.size());
    basis->to_samples(coefficients, 3, out);
    return out;
  }
  std::span<const double> values() const override { return coefficients; }
  std::span<double> values() override { return coefficients; }
  /// profile.csv: R(r) in 1/mm² at the basis's radii.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

/// Displacements (mm), 3 per point: first `probe_count` probe points (at
/// the rest positions probe_rest_mm, 3 per probe), then every node of the
/// simulator's mesh (a goal may hold probes only).
struct DisplacementsObservation final : ObservationOf<DisplacementsObservation> {
  static constexpr std::string_view kType = "displacements";
  std::vector<double> xyz_mm;
  int probe_count = 0;
  std::vector<double> probe_rest_mm;
  /// Per-tet von Mises stress (MPa; 0 in void) and its largest value and
  /// 99th percentile over the solid's tets, for goals that bound stress.
  std::vector<double> von_mises_mpa;
  double stress_max_mpa = 0, stress_p99_mpa = 0;
  std::span<const double> probes() const { return {xyz_mm.data(), 3 * static_cast<size_t>(probe_count)}; }
  std::span<const double> values() const override { return xyz_mm; }
  std::span<double> values() override { return xyz_mm; }
  /// observation.csv: probes first, then nodes.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

/// Plain numbers (e.g. a coverage fraction, a scalar response).
struct VectorObservation final : ObservationOf<VectorObservation> {
  static constexpr std::string_view kType = "vector";
  std::vector<double> data;
  std::span<const double> values() const override { return data; }
  std::span<double> values() override { return data; }
};

/// The linear RGB albedo of one surface patch.
struct AlbedoObservation final : ObservationOf<AlbedoObservation> {
  static constexpr std::string_view kType = "albedo";
  std::array<double, 3> rgb{};
  std::span<const double> values() const override { return rgb; }
  std::span<double> values() override { return rgb; }
  /// albedo.csv (linear and 8-bit sRGB) and an sRGB swatch, albedo.png.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

}  // namespace spec2fab
