#pragma once
/// Values that parts of one run share because they are costly to make and
/// the same for every part that asks — tabulated albedos, layer spectra, a
/// tet mesh — keyed by their type and by the content they are made from.
///
/// A run (an experiment, a `spec2fab simulate`) owns one RunCache and hands
/// it to its parts through PartContext, so what is cached lives exactly as
/// long as the run: nothing leaks from one run into the next in the same
/// process (tests, a batch of experiments), and nothing is process-wide.
/// A process that prepares many runs on purpose (the fuzz harnesses) hands
/// them one session cache instead (`session` of prepare_experiment and
/// prepare_simulation), bounded by count and weight: its keys are the
/// content each value is made from, so one run's value serves the next only
/// where it would be made the same.

#include <concepts>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeindex>
#include <utility>

namespace spec2fab {

/// What a cached value weighs against a RunCache's byte budget: a type that
/// holds a large table says so with a member `std::size_t cached_bytes()
/// const`; a vector of plain values (an albedo table) weighs its storage;
/// any other counts as its sizeof. A value that fills itself in later
/// (LayerStackModel) is weighed as it was made.
template <class T>
std::size_t cached_bytes_of(const T& value) {
  if constexpr (requires { { value.cached_bytes() } -> std::convertible_to<std::size_t>; })
    return value.cached_bytes();
  else if constexpr (requires { typename T::value_type; { value.capacity() } -> std::convertible_to<std::size_t>; })
    return sizeof(T) + value.capacity() * sizeof(typename T::value_type);
  else
    return sizeof(T);
}

class RunCache {
 public:
  /// Unbounded: a run's cache keeps every value for the run's lifetime.
  RunCache() = default;
  /// At most `capacity` values (at least 1) weighing at most `byte_budget`
  /// together (cached_bytes_of), least recently asked for dropped first;
  /// the value just made always stays, however heavy. The count alone
  /// does not bound memory where keys come from the input: a fuzzed
  /// "samples" of 4096 makes a 134 MB radial basis, and with 256 values
  /// like it cached fuzz_simulate grew to 3.2 GB in an hour.
  explicit RunCache(size_t capacity, size_t byte_budget = static_cast<size_t>(-1))
      : capacity_(capacity < 1 ? 1 : capacity), byte_budget_(byte_budget) {}

  /// The value of type T stored under `key`, made by `make()` (returning a
  /// std::shared_ptr<T>) on the first request. T may be const; a value that
  /// fills itself in lazily (and is thread-safe doing so) is asked for as
  /// non-const. Thread-safe: `make` runs once per key, under the cache's
  /// lock, so a part that asks while another makes the same value waits for
  /// it instead of making it again.
  template <class T, class Make>
  std::shared_ptr<T> get(const std::string& key, Make&& make) {
    std::lock_guard lock(mutex_);
    auto& entry = entries_[{std::type_index(typeid(T)), key}];
    entry.last_asked = ++asked_;
    if (!entry.value) {
      std::shared_ptr<T> made(make());
      entry.bytes = made ? cached_bytes_of(*made) : 0;
      entry.value = std::const_pointer_cast<std::remove_const_t<T>>(std::move(made));
      bytes_ += entry.bytes;
      while (entries_.size() > 1 && (entries_.size() > capacity_ || bytes_ > byte_budget_)) drop_least_recent();
    }
    return std::static_pointer_cast<T>(entry.value);
  }

  /// Values held (for tests and logs).
  size_t size() const {
    std::lock_guard lock(mutex_);
    return entries_.size();
  }
  /// What the values held weigh (cached_bytes_of).
  size_t bytes() const {
    std::lock_guard lock(mutex_);
    return bytes_;
  }

 private:
  struct Entry {
    std::shared_ptr<void> value;
    unsigned long long last_asked = 0;
    size_t bytes = 0;
  };
  // The entry asked for longest ago (never the one just made: it was asked last).
  void drop_least_recent() {
    auto oldest = entries_.begin();
    for (auto it = entries_.begin(); it != entries_.end(); ++it)
      if (it->second.last_asked < oldest->second.last_asked) oldest = it;
    bytes_ -= oldest->second.bytes;
    entries_.erase(oldest);
  }

  mutable std::mutex mutex_;
  size_t capacity_ = static_cast<size_t>(-1);
  size_t byte_budget_ = static_cast<size_t>(-1);
  size_t bytes_ = 0;
  unsigned long long asked_ = 0;
  std::map<std::pair<std::type_index, std::string>, Entry> entries_;
};

/// A key's part for a value made from a table (a goal image's pixels): the
/// table's length and a 64-bit hash of its bytes.
template <class T>
  requires std::is_trivially_copyable_v<T>
std::string content_key(std::span<const T> values) {
  const std::string_view bytes(reinterpret_cast<const char*>(values.data()), values.size_bytes());
  return std::to_string(values.size()) + "#" + std::to_string(std::hash<std::string_view>{}(bytes));
}

/// `cache->get<T>(key, make)`, or make() alone when there is no cache (a
/// part built outside any run, e.g. in a unit test).
template <class T, class Make>
std::shared_ptr<T> cached(RunCache* cache, const std::string& key, Make&& make) {
  if (cache) return cache->get<T>(key, std::forward<Make>(make));
  return std::shared_ptr<T>(make());
}

}  // namespace spec2fab
