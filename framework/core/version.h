#pragma once
/// Spec2Fab's version: the one in the top CMakeLists.txt's project() call,
/// compiled into core/version.cpp — the only place it is written.

namespace spec2fab {

/// "major.minor.patch", e.g. "0.1.0".
const char* version();

}  // namespace spec2fab
