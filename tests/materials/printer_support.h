#pragma once
// A printer profile read from JSON text, as the tests of the materials
// folder write them.

#include <string>

#include "core/properties.h"
#include "materials/printer_profile.h"

namespace spec2fab::testing {

/// The profile `text` describes, read as the file `origin`; every key must be read.
inline PrinterProfile printer_from(const std::string& text, const std::string& origin = "printer.json") {
  const Properties properties = Properties::parse(text, origin);
  PrinterProfile printer = PrinterProfile::from_properties(properties);
  properties.check_all_read();
  return printer;
}

}  // namespace spec2fab::testing
