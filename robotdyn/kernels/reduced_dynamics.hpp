// robotdyn/kernels/reduced_dynamics.hpp: the equations of motion in the independent velocities, twin of
// robotdyn/reduction/reduced_dynamics.py (D'Alembert with v = S nu, a = S nudot + w):
//
//   M_r = S^T M S,  h = C_r nu + g_r = S^T RNEA(q, S nu, w) = S^T (C v + g + M w),  g_r = S^T g,  B_r = S^T B
//
// here from two Pinocchio passes per state: CRBA in the WORLD convention (M, the joint Jacobians, and from its
// composite inertias g_k = -J_k^T (Y_subtree(k) a_g), the torque that holds the subtree's weight) and RNEA without
// gravity at zero joint acceleration (C v).
#pragma once

#include "common.hpp"

namespace robotdyn {
namespace kernels {

// g (nv) from CRBA's composite inertias (data.oYcrb) and world joint Jacobians (data.J), gravity the model's
// (a Pinocchio model whose own gravity is zero).
inline void gravity_torques(const pin::Model& model, const pin::Data& data, const pin::Motion& gravity, int nv,
                            VectorXd& g) {
  g.resize(nv);
  for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model.njoints); ++i) {
    const int col = model.joints[i].idx_v();
    const pin::Force weight = data.oYcrb[i] * gravity;
    g[col] = -(data.J.col(col).head<3>().dot(weight.linear()) + data.J.col(col).tail<3>().dot(weight.angular()));
  }
}

// Whether bias_forces may run on this model: every joint a 1-dof revolute or prismatic joint (axis-aligned or not),
// whose joint velocity Pinocchio computes without q (calc(data, Blank, v)) and whose bias acceleration c is zero.
inline bool bias_forces_apply(const pin::Model& model) {
  for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model.njoints); ++i) {
    const std::string kind = model.joints[i].shortname();
    if (!(kind == "JointModelRX" || kind == "JointModelRY" || kind == "JointModelRZ" || kind == "JointModelPX" ||
          kind == "JointModelPY" || kind == "JointModelPZ" || kind == "JointModelRevoluteUnaligned" ||
          kind == "JointModelPrismaticUnaligned"))
      return false;
  }
  return true;
}

// The joint models bias_forces runs on (those of bias_forces_apply): 1-dof revolute and prismatic joints, which
// compute their velocity without q (calc(data, Blank, v)) and have no bias acceleration. (A composite joint holding
// a mimic joint does not compile with a velocity-only calc.)
template <class JointModel>
struct VelocityOnlyCalc : std::false_type {};
template <int axis>
struct VelocityOnlyCalc<pin::JointModelRevoluteTpl<double, 0, axis>> : std::true_type {};
template <int axis>
struct VelocityOnlyCalc<pin::JointModelPrismaticTpl<double, 0, axis>> : std::true_type {};
template <>
struct VelocityOnlyCalc<pin::JointModelRevoluteUnalignedTpl<double, 0>> : std::true_type {};
template <>
struct VelocityOnlyCalc<pin::JointModelPrismaticUnalignedTpl<double, 0>> : std::true_type {};

// RNEA's forward step (Pinocchio's RneaForwardStep, src/algorithm/rnea.hxx, operation for operation) on joint
// placements already in data: the joint placements jdata.M and data.liMi are CRBA's at the same q (computed by the
// same formula), so only the joint velocity is recomputed (calc(jdata, Blank, v)).
struct BiasForwardStep : pin::fusion::JointUnaryVisitorBase<BiasForwardStep> {
  typedef boost::fusion::vector<const pin::Model&, pin::Data&, const VectorXd&, const VectorXd&> ArgsType;
  template <typename JointModel>
  static void algo(const pin::JointModelBase<JointModel>& jmodel,
                   pin::JointDataBase<typename JointModel::JointDataDerived>& jdata, const pin::Model& model,
                   pin::Data& data, const VectorXd& v, const VectorXd& a) {
    if constexpr (!VelocityOnlyCalc<JointModel>::value) {  // (never reached: bias_forces_apply refuses them)
      throw std::logic_error("bias_forces on a joint without a velocity-only calc");
    } else {
      algo_velocity(jmodel, jdata, model, data, v, a);
    }
  }
  template <typename JointModel>
  static void algo_velocity(const pin::JointModelBase<JointModel>& jmodel,
                            pin::JointDataBase<typename JointModel::JointDataDerived>& jdata, const pin::Model& model,
                            pin::Data& data, const VectorXd& v, const VectorXd& a) {
    const pin::JointIndex i = jmodel.id();
    const pin::JointIndex parent = model.parents[i];
    jmodel.derived().calc(jdata.derived(), pin::Blank(), v);
    data.v[i] = jdata.v();
    if (parent > 0) data.v[i] += data.liMi[i].actInv(data.v[parent]);
    data.a_gf[i] = jdata.c() + (data.v[i] ^ jdata.v());
    data.a_gf[i] += jdata.S() * jmodel.JointMappedVelocitySelector(a);
    data.a_gf[i] += data.liMi[i].actInv(data.a_gf[parent]);
    model.inertias[i].__mult__(data.v[i], data.h[i]);
    model.inertias[i].__mult__(data.a_gf[i], data.f[i]);
    data.f[i] += data.v[i].cross(data.h[i]);
  }
};

// pin::rnea(model, data, q, v, a) after pin::crba(model, data, q, WORLD) at the same q, on a model for which
// bias_forces_apply holds: the same numbers bit for bit (data.tau, data.v, data.a_gf, data.f), without computing
// the joint placements a second time. In robotdyn a is zero and the model's gravity is zero: data.tau = C(q, v) v.
inline void bias_forces(const pin::Model& model, pin::Data& data, const VectorXd& v, const VectorXd& a) {
  data.tau.setZero();
  data.v[0].setZero();
  data.a_gf[0] = -model.gravity;
  BiasForwardStep::ArgsType arg1(model, data, v, a);
  for (pin::JointIndex i = 1; i < static_cast<pin::JointIndex>(model.njoints); ++i)
    BiasForwardStep::run(model.joints[i], data.joints[i], arg1);
  typedef pin::impl::RneaBackwardStep<double, 0, pin::JointCollectionDefaultTpl> Pass2;
  Pass2::ArgsType arg2(model, data);
  for (pin::JointIndex i = static_cast<pin::JointIndex>(model.njoints) - 1; i > 0; --i)
    Pass2::run(model.joints[i], data.joints[i], arg2);
  data.tau.array() += model.armature.array() * a.array();
}

// M_r, h, g_r, B_r from M (CRBA's upper triangle: its lower one is filled here), S, g, Cv (RNEA's C v: g is added to
// it in place, so it holds C v + g after), w and B; SM = M S is kept (the slipping wheels' system and the constraint
// forces use it). S, g, w and B are read only (non-const references: Eigen's products of non-const operands, which
// GCC inlines where it does not inline those of const ones; measured 10 -> 16 us per evaluation on MMR12-EOD).
inline void reduce(MatrixXd& M, MatrixXd& S, VectorXd& g, VectorXd& Cv, VectorXd& w, MatrixXd& B, MatrixXd& SM,
                   MatrixXd& Mr, VectorXd& hr, VectorXd& gr, MatrixXd& Br) {
  M.triangularView<Eigen::StrictlyLower>() = M.transpose().triangularView<Eigen::StrictlyLower>();
  SM.noalias() = M.lazyProduct(S);
  Mr.noalias() = S.transpose().lazyProduct(SM);
  gr.noalias() = S.transpose() * g;
  Cv += g;
  hr.noalias() = S.transpose() * Cv;
  hr.noalias() += SM.transpose() * w;
  Br.noalias() = S.transpose().lazyProduct(B);
}

}  // namespace kernels
}  // namespace robotdyn
