// What a bake will need in memory, known before its expensive steps, and what the process has.
//
// The bake's peak is the stiffness matrix, CHOLMOD's factor of K − σM and the dense vectors of its
// widest step. The factor's size is known from CHOLMOD's symbolic analysis, before the numeric
// factorisation (where a raw scan would run out, long into the bake); the rest follows from the
// counts. Measured peaks against this estimate: bench/results/raw_scan.json.
#pragma once

#include "util/types.h"

namespace modal_deform {

struct BakeMemory {
  double mesh = 0;       // the mesh, its topology, the energy's terms and the mass (bytes)
  double stiffness = 0;  // K and the triangle CHOLMOD factors (with its temporary copy)
  double factor = 0;     // CHOLMOD's supernodal factor, from the symbolic analysis
  double vectors = 0;    // the dense vectors alive at the widest step of the bake
  double total() const { return mesh + stiffness + factor + vectors; }
};

// The peak of a bake of a mesh of `vertices` vertices, `simulated` of them simulated, with a
// stiffness matrix of `stiffness_nonzeros` entries whose factor takes `factor_bytes`
// (CholmodLLT::factor_bytes after analyze), `modes` modes asked for and `derivatives`.
BakeMemory estimate_bake_memory(Eigen::Index vertices, Eigen::Index simulated,
                                double stiffness_nonzeros, double factor_bytes, int modes,
                                int derivatives);

// Bytes this process can still allocate: the smaller of the system's available memory
// (MemAvailable) and the address-space limit (ulimit -v) less what the process has mapped;
// infinity when neither can be read.
double available_memory();

// Throws OutOfMemory, itemising `need`, when it exceeds `available` (bytes).
void require_memory(const BakeMemory& need, double available);

}  // namespace modal_deform
