// The bake's stages by name, apart from the progress reporter (util/progress.h) that carries them:
// the bake (cpp/bake/bake.h) and the steps below it whose work a stage is (the ghost's edge
// collapse, the pencil's modes and derivative solves, the orthonormalisation) report under them.
#pragma once

#include <array>

namespace modal_deform {

// The bake's stages in the order they run (cpp/bake/bake.h): the names its progress reports and
// Basis::timings use, exported to Python as BAKE_STAGES so that one bar runs over the whole bake.
// A bake without a proxy skips the first and the last.
namespace stages {
inline constexpr const char* kProxy = "proxy";
inline constexpr const char* kAttachment = "attachment";
inline constexpr const char* kHessian = "hessian";
inline constexpr const char* kFactorisation = "factorisation";
inline constexpr const char* kGhost = "ghost";
inline constexpr const char* kModes = "modes";
inline constexpr const char* kThirdDerivatives = "third derivatives";
inline constexpr const char* kDerivativeSolves = "derivative solves";
inline constexpr const char* kOrthonormalisation = "orthonormalisation";
inline constexpr const char* kAssembly = "assembly";
inline constexpr const char* kProlongation = "prolongation";
}  // namespace stages
inline constexpr std::array<const char*, 11> kBakeStages = {stages::kProxy,
                                                            stages::kAttachment,
                                                            stages::kHessian,
                                                            stages::kFactorisation,
                                                            stages::kGhost,
                                                            stages::kModes,
                                                            stages::kThirdDerivatives,
                                                            stages::kDerivativeSolves,
                                                            stages::kOrthonormalisation,
                                                            stages::kAssembly,
                                                            stages::kProlongation};

}  // namespace modal_deform
