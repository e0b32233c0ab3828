#include "modes/vibration_modes.h"

namespace modal_deform {

VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count,
                               Progress* progress) {
  return vibration_modes(K, mass, count, Eigen::MatrixXd(K.rows(), 0), progress);
}

VibrationModes vibration_modes(const SparseMatrix& K, const VectorRef& mass, int count,
                               const Eigen::Ref<const Eigen::MatrixXd>& Z, Progress* progress) {
  ShiftedPencil pencil(K, mass, Z);
  VibrationModes modes = pencil.lowest_modes(count, progress);
  require_accurate(modes, 0, count);
  return modes;
}

}  // namespace modal_deform
