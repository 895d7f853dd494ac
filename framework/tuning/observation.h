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
///
/// Here are the types several simulators and goals share (images, vectors,
/// albedo); a type one simulator alone makes lives with it
/// (subsurface/radial_profile.h, fem/displacements.h).

#include <array>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

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
  /// The values' shape, outermost axis first; values() is their row-major
  /// flat form (an image's height × width × channels). How the Python module
  /// hands them over as arrays; by default one axis.
  virtual std::vector<std::size_t> shape() const { return {values().size()}; }
  /// Makes room for values of `shape` (as shape() gives it), for parts
  /// written outside C++ that hand values over (a Python simulator or goal);
  /// false when the type cannot take that shape (the default: none).
  virtual bool reshape(std::span<const std::size_t> /*shape*/) { return false; }
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
  /// height × width, × channels when there are several.
  std::vector<std::size_t> shape() const override;
  bool reshape(std::span<const std::size_t> shape) override;
  /// image.png (sRGB, 8 bit; scaled so the brightest is white when values exceed 1).
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};



/// Plain numbers (e.g. a coverage fraction, a scalar response).
struct VectorObservation final : ObservationOf<VectorObservation> {
  static constexpr std::string_view kType = "vector";
  std::vector<double> data;
  std::span<const double> values() const override { return data; }
  std::span<double> values() override { return data; }
  bool reshape(std::span<const std::size_t> shape) override;
};

/// The linear RGB albedo of one surface patch.
struct AlbedoObservation final : ObservationOf<AlbedoObservation> {
  static constexpr std::string_view kType = "albedo";
  std::array<double, 3> rgb{};
  std::span<const double> values() const override { return rgb; }
  std::span<double> values() override { return rgb; }
  bool reshape(std::span<const std::size_t> shape) override { return shape.size() == 1 && shape[0] == 3; }
  /// albedo.csv (linear and 8-bit sRGB) and an sRGB swatch, albedo.png.
  std::vector<std::string> write_files(const std::filesystem::path& folder) const override;
};

}  // namespace spec2fab
