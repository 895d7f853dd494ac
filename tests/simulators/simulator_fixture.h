#pragma once
// A fixture for simulator tests: the PolyJet library on the J750 palette,
// subtrees from JSON, and one registered simulator run on a subtree.

#include <gtest/gtest.h>

#include <string>

#include "materials/material_library.h"
#include "materials/palette.h"
#include "materials/printer_profile.h"
#include "reducer/node.h"
#include "tuning/parts.h"

namespace spec2fab {

class SimulatorTest : public ::testing::Test {
 protected:
  SimulatorTest()
      : library_(MaterialLibrary::load(SPEC2FAB_DATASETS_DIR "/materials/polyjet.json")),
        printer_(PrinterProfile::load(SPEC2FAB_DATASETS_DIR "/printers/j750.json")),
        palette_(library_, printer_) {}

  NodePtr node(const std::string& json) const {
    return build_node(Properties::parse(json, "subtree.json"), NodeContext{palette_});
  }

  /// Sets up and runs the simulator registered as `name` once on `subtree`.
  template <class O>
  O simulate(const std::string& name, const ReducerNode& subtree, const std::string& options) const {
    const PartContext context{palette_};
    auto simulator = SimulatorRegistry::instance().create_named(
        name, Properties::parse(options, "options.json"), "simulator", context);
    simulator->setup(subtree, SimulationDomain());
    auto out = simulator->make_observation();
    simulator->simulate(subtree, *out);
    return static_cast<O&>(*out);
  }

  MaterialLibrary library_;
  PrinterProfile printer_;
  MaterialPalette palette_;
};

}  // namespace spec2fab
