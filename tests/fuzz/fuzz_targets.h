// The fuzz targets: each decodes bytes (fuzz_input.h) into inputs for a group of native entry
// points and checks the core's promises: an entry point either succeeds with finite outputs that
// satisfy its contract, or throws InputError or NumericalError with a message. Anything else (a
// crash, another exception, NaN or infinity in an output, a result out of range) is a Failure.
//
// The libFuzzer binaries (fuzz_main.cpp, `make fuzz`) abort on a Failure; the C++ test suite
// replays every file under tests/fuzz/corpus/<target>/ (seeds and former crashes) through them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>

namespace modal_deform::fuzz {

struct Failure : std::logic_error {
  using std::logic_error::logic_error;
};

// check_mesh, lumped_mass, both energies (value, gradient, Hessian, third derivative at rest and
// at a deformed state) and ghost_mesh on a mesh of up to 24 vertices.
void mesh_entry_points(const std::uint8_t* data, std::size_t size);

// bake on a mesh of up to 14 vertices with fuzzed options, then posing what it baked: the
// reduced solver (handles, transforms, solve, positions) and solve_full.
void bake_and_pose(const std::uint8_t* data, std::size_t size);

// validate_basis on arrays of fuzzed shapes and contents, and for those it accepts the reduced
// solver: construction, set_transforms, solve, positions.
void stored_basis(const std::uint8_t* data, std::size_t size);

}  // namespace modal_deform::fuzz
