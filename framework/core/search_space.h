#pragma once
/// The free parameters of a reducer subtree (the paper's getSearchSpace), with
/// get/set as one vector so that optimizers see plain numbers.

#include <string>
#include <vector>

#include "core/parameter.h"

namespace spec2fab {

class SearchSpace {
 public:
  struct Entry {
    std::string name;  ///< path in the tree, e.g. "shell/columns/12/layers/0/thickness_mm"
    Parameter* parameter;
  };

  void add(std::string name, Parameter* parameter) { entries_.push_back({std::move(name), parameter}); }

  size_t dimension() const { return entries_.size(); }
  const std::vector<Entry>& entries() const { return entries_; }
  const Parameter& parameter(size_t i) const { return *entries_[i].parameter; }

  std::vector<double> values() const;
  /// Sets every free parameter (values are snapped to what each admits).
  void set_values(const std::vector<double>& values);
  std::vector<double> lower_bounds() const;
  std::vector<double> upper_bounds() const;

 private:
  std::vector<Entry> entries_;
};

}  // namespace spec2fab
