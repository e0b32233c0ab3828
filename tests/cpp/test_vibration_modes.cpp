#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <string>

#include "mesh/mass.h"
#include "mesh/mesh_topology.h"
#include "mesh/primitives.h"
#include "modes/rigid_motions.h"
#include "modes/shifted_pencil.h"
#include "modes/stiffness_and_mass.h"
#include "modes/vibration_modes.h"
#include "stand_in_stiffness.h"
#include "test_support.h"
#include "util/errors.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;
using testing::jittered_bar;
using testing::laplacian_stiffness;
using testing::shared_mesh;
using testing::side_by_side;
using testing::spring_network_hessian;

// Two rigid spring networks side by side: two components.
TriangleMesh two_boxes() {
  return side_by_side(jittered_bar(2, 2, 3, 0.05, 1), jittered_bar(1, 2, 2, 0.05, 2),
                      Eigen::RowVector3d(3, 0, 0));
}

// Eigenvalues below this fraction of the first nonzero one count as zero.
int count_zero(const Eigen::VectorXd& eigenvalues, double first_nonzero) {
  return static_cast<int>((eigenvalues.array().abs() < 1e-8 * first_nonzero).count());
}

void expect_m_orthonormal(const Eigen::MatrixXd& Phi, const Eigen::VectorXd& m) {
  const Eigen::MatrixXd gram = Phi.transpose() * m.asDiagonal() * Phi;
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(Phi.cols(), Phi.cols())).cwiseAbs().maxCoeff(),
            1e-10);
}

TEST(VibrationModes, MatchDenseGeneralizedEigensolver) {
  const TriangleMesh mesh = two_boxes();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const Eigen::VectorXd m = dof_masses(mass);
  for (const SparseMatrix& K :
       {spring_network_hessian(mesh.V, mesh.F), laplacian_stiffness(mesh.V, mesh.F)}) {
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> dense(
        Eigen::MatrixXd(K), Eigen::MatrixXd(m.asDiagonal()));
    const int count = 20;
    const VibrationModes modes = vibration_modes(K, mass, count);
    ASSERT_EQ(modes.eigenvalues.size(), count);
    ASSERT_EQ(modes.modes.rows(), K.rows());
    ASSERT_EQ(modes.modes.cols(), count);
    const double top = dense.eigenvalues()[count - 1];
    for (int i = 0; i < count; ++i) {
      EXPECT_NEAR(modes.eigenvalues[i], dense.eigenvalues()[i], 1e-9 * top) << "eigenvalue " << i;
      const Eigen::VectorXd r =
          K * modes.modes.col(i) - modes.eigenvalues[i] * m.cwiseProduct(modes.modes.col(i));
      EXPECT_NEAR(modes.residuals[i], std::sqrt(r.cwiseAbs2().cwiseQuotient(m).sum()), 1e-14 * top);
      EXPECT_LT(modes.residuals[i], 1e-8 * top) << "mode " << i;
    }
    expect_m_orthonormal(modes.modes, m);
    EXPECT_LT(modes.shift, 0.0);
    EXPECT_GT(modes.solves, count);
  }
}

TEST(VibrationModes, SixZeroModesPerComponentForSpringsThreeForTheLaplacian) {
  const TriangleMesh mesh = two_boxes();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const VibrationModes springs = vibration_modes(spring_network_hessian(mesh.V, mesh.F), mass, 16);
  EXPECT_EQ(count_zero(springs.eigenvalues, springs.eigenvalues[12]), 12);
  const VibrationModes laplacian = vibration_modes(laplacian_stiffness(mesh.V, mesh.F), mass, 10);
  EXPECT_EQ(count_zero(laplacian.eigenvalues, laplacian.eigenvalues[6]), 6);
}

TEST(VibrationModes, BunnyHasSixZeroModesAndAccurateResiduals) {
  const TriangleMesh& bunny = shared_mesh("bunny.obj.gz");
  const Eigen::VectorXd mass = lumped_mass(bunny.V, bunny.F);
  const VibrationModes modes = vibration_modes(spring_network_hessian(bunny.V, bunny.F), mass, 20);
  EXPECT_EQ(count_zero(modes.eigenvalues, modes.eigenvalues[6]), 6);
  EXPECT_LT(modes.residuals.maxCoeff(), 1e-9 * modes.eigenvalues[19]);
  expect_m_orthonormal(modes.modes, dof_masses(mass));
  for (int i = 1; i < 20; ++i) EXPECT_LE(modes.eigenvalues[i - 1], modes.eigenvalues[i]);
}

TEST(VibrationModes, DeflatingTheRigidMotionsLeavesTheFlexibleModes) {
  const TriangleMesh mesh = two_boxes();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const Eigen::VectorXd m = dof_masses(mass);
  const SparseMatrix K = spring_network_hessian(mesh.V, mesh.F);
  const std::vector<int> labels = build_topology(mesh.V, mesh.F).vertex_component;
  const Eigen::MatrixXd Z = rigid_motions(
      mesh.V,
      Eigen::Map<const Eigen::VectorXi>(labels.data(), static_cast<Eigen::Index>(labels.size())),
      mass);
  const VibrationModes all = vibration_modes(K, mass, 20);
  const VibrationModes flexible = vibration_modes(K, mass, 8, Z);
  const double top = all.eigenvalues[19];
  for (int i = 0; i < 8; ++i)
    EXPECT_NEAR(flexible.eigenvalues[i], all.eigenvalues[12 + i], 1e-9 * top) << "mode " << i;
  EXPECT_LT((Z.transpose() * m.asDiagonal() * flexible.modes).cwiseAbs().maxCoeff(), 1e-10);
  // The same modes up to sign (the eigenvalues are distinct).
  const Eigen::MatrixXd overlap =
      all.modes.middleCols(12, 8).transpose() * m.asDiagonal() * flexible.modes;
  EXPECT_LT((overlap.cwiseAbs() - Eigen::MatrixXd::Identity(8, 8)).cwiseAbs().maxCoeff(), 1e-6);
  expect_m_orthonormal(flexible.modes, m);
  EXPECT_LT(flexible.solves, all.solves);
  // Z must be M-orthonormal, and count leaves room for the deflated kernel.
  EXPECT_THROW(vibration_modes(K, mass, 8, 2 * Z), InputError);
  EXPECT_THROW(vibration_modes(K, mass, static_cast<int>(K.rows()) - 12, Z), InputError);
}

TEST(VibrationModes, ReportedResidualsAreCheckedOnRequest) {
  const TriangleMesh mesh = two_boxes();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const SparseMatrix K = spring_network_hessian(mesh.V, mesh.F);
  const std::vector<int> labels = build_topology(mesh.V, mesh.F).vertex_component;
  const Eigen::MatrixXd Z = rigid_motions(
      mesh.V,
      Eigen::Map<const Eigen::VectorXi>(labels.data(), static_cast<Eigen::Index>(labels.size())),
      mass);
  ShiftedPencil pencil(K, mass, Z);
  VibrationModes modes = pencil.lowest_modes(8);
  ASSERT_EQ(modes.tolerances.size(), 8);
  EXPECT_TRUE((modes.residuals.array() <= modes.tolerances.array()).all());
  EXPECT_TRUE((modes.tolerances.array() > 0).all());
  modes.residuals[2] = 2 * modes.tolerances[2];
  EXPECT_NO_THROW(require_accurate(modes, 3, 8));
  try {
    require_accurate(modes, 0, 8);
    ADD_FAILURE() << "no exception";
  } catch (const NumericalError& e) {
    EXPECT_NE(std::string(e.what()).find("mode 2 ("), std::string::npos) << e.what();
  }
}

// The shifted pencil deflates modes it found: the 12 zero modes of two spring networks, without
// their rigid motions given, then the flexible modes above them, as with the rigid motions given.
TEST(VibrationModes, DeflatedZeroModesLeaveTheFlexibleModes) {
  const TriangleMesh mesh = two_boxes();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const Eigen::VectorXd m = dof_masses(mass);
  const SparseMatrix K = spring_network_hessian(mesh.V, mesh.F);
  ShiftedPencil pencil(K, mass, Eigen::MatrixXd(K.rows(), 0));
  const VibrationModes all = pencil.lowest_modes(20);
  const double undeflated_shift = pencil.shift();
  pencil.deflate(12);
  ASSERT_EQ(pencil.kernel().cols(), 12);
  const VibrationModes flexible = pencil.lowest_modes(8);
  EXPECT_GT(pencil.shift(), undeflated_shift);  // closer to 0 with the kernel deflated
  const double top = all.eigenvalues[19];
  for (int i = 0; i < 8; ++i)
    EXPECT_NEAR(flexible.eigenvalues[i], all.eigenvalues[12 + i], 1e-9 * top) << "mode " << i;
  EXPECT_LT((pencil.kernel().transpose() * m.asDiagonal() * flexible.modes).cwiseAbs().maxCoeff(),
            1e-10);
  expect_m_orthonormal(flexible.modes, m);
  expect_input_error([&] { pencil.deflate(9); }, "deflate:");
}

TEST(VibrationModes, UnreferencedVertexStaysStill) {
  TriangleMesh mesh = jittered_bar(2, 2, 2, 0.05);
  mesh.V.conservativeResize(mesh.V.rows() + 1, 3);
  mesh.V.row(mesh.V.rows() - 1) << 5, 5, 5;
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  ASSERT_EQ(mass[mass.size() - 1], 0.0);
  const VibrationModes modes = vibration_modes(spring_network_hessian(mesh.V, mesh.F), mass, 10);
  EXPECT_EQ(modes.modes.bottomRows(3).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(count_zero(modes.eigenvalues, modes.eigenvalues[6]), 6);
}

TEST(VibrationModes, ReportsProgressAndCancels) {
  const TriangleMesh mesh = two_boxes();
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const SparseMatrix K = spring_network_hessian(mesh.V, mesh.F);
  std::vector<double> fractions;
  Progress progress(
      [&](const std::string& stage, double fraction) {
        EXPECT_EQ(stage, "modes");
        fractions.push_back(fraction);
        return true;
      },
      0.0);
  vibration_modes(K, mass, 12, &progress);
  ASSERT_GT(fractions.size(), 5u);  // one report per block solve
  EXPECT_EQ(fractions.front(), 0.0);
  EXPECT_EQ(fractions.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  int calls = 0;
  Progress cancel([&](const std::string&, double) { return ++calls < 5; }, 0.0);
  EXPECT_THROW(vibration_modes(K, mass, 12, &cancel), Cancelled);
  EXPECT_EQ(calls, 5);
}

TEST(VibrationModes, RejectsBadInput) {
  const TriangleMesh mesh = jittered_bar(1, 1, 2, 0.05);
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const SparseMatrix K = spring_network_hessian(mesh.V, mesh.F);
  EXPECT_THROW(vibration_modes(K, mass, 0), InputError);
  EXPECT_THROW(vibration_modes(K, mass, static_cast<int>(K.rows())), InputError);
  EXPECT_THROW(vibration_modes(K, mass.head(mass.size() - 1), 4), InputError);
  Eigen::VectorXd negative = mass;
  negative[3] = -1;
  EXPECT_THROW(vibration_modes(K, negative, 4), InputError);
  SparseMatrix asymmetric = K;
  asymmetric.coeffRef(0, 5) += 1.0;
  try {
    vibration_modes(asymmetric, mass, 4);
    ADD_FAILURE() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not symmetric"), std::string::npos) << e.what();
  }
  EXPECT_THROW(vibration_modes(SparseMatrix(K.rows(), K.cols()), mass, 4), InputError);
  // Indefinite: K − σM cannot be factored for σ < 0.
  SparseMatrix indefinite = K;
  indefinite.coeffRef(0, 0) *= -1;
  EXPECT_THROW(vibration_modes(indefinite, mass, 4), NumericalError);
}

// Every asymmetry is found, whichever triangle holds it and whether its partner is stored, and
// the message names the pair; explicit zeros without a partner are symmetric.
TEST(VibrationModes, SymmetryCheckPairsEveryEntry) {
  const TriangleMesh mesh = jittered_bar(1, 1, 2, 0.05);
  const Eigen::VectorXd mass = lumped_mass(mesh.V, mesh.F);
  const SparseMatrix K = spring_network_hessian(mesh.V, mesh.F);
  const int last = static_cast<int>(K.rows()) - 1;
  ASSERT_EQ(K.coeff(0, last), 0.0);  // the bar's two ends are not coupled
  validate_stiffness_and_mass(K, mass);
  for (const auto& [i, j] :
       std::vector<std::pair<int, int>>{{0, last}, {last, 0}, {4, 2}, {2, 4}, {last, last - 1}}) {
    SparseMatrix changed = K;
    changed.coeffRef(i, j) += 1.0;
    for (SparseMatrix matrix : {changed, SparseMatrix(changed.transpose())}) {
      matrix.makeCompressed();
      testing::expect_input_error([&] { validate_stiffness_and_mass(matrix, mass); },
                                  "not symmetric");
    }
    changed.coeffRef(j, i) += 1.0;  // symmetric again
    validate_stiffness_and_mass(changed, mass);
  }
  SparseMatrix zeros = K;
  zeros.coeffRef(0, last) = 0.0;  // stored, no partner
  zeros.coeffRef(last - 2, 1) = 0.0;
  validate_stiffness_and_mass(zeros, mass);
  zeros.coeffRef(last - 2, 1) = 1e-3;
  testing::expect_input_error([&] { validate_stiffness_and_mass(zeros, mass); },
                              "K(" + std::to_string(last - 2) + ", 1) = 0.001 but K(1, " +
                                  std::to_string(last - 2) + ") = 0");
}

}  // namespace
}  // namespace modal_deform
