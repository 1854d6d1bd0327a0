// Pinocchio's own C++ cost of rnea / aba / crba on the rc3r arm, for `benchmarks/cpp_pinocchio.py`.
//
// Usage: pin_cpp_bench MODEL.txt [N] [repeats]
// MODEL.txt (written by cpp_pinocchio.py from rc3r.urdf.load_arm): first line "g0", then one line
// per joint (all revolute about their local z axis, JointModelRZ):
//   parent  R(9, row-major)  p(3)  mass  com(3)  inertia about the com(9, row-major)
// Prints one JSON line: median and min seconds per call over `repeats` timed passes of N random
// states (after one warm-up pass), and tau at a fixed state for the caller's cross-check.
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <vector>

using Clock = std::chrono::steady_clock;

template <class F>
static double per_call(F f, int n, int repeats, double* best) {
  std::vector<double> ts;
  f();  // warm-up
  for (int r = 0; r < repeats; ++r) {
    auto t0 = Clock::now();
    f();
    ts.push_back(std::chrono::duration<double>(Clock::now() - t0).count() / n);
  }
  std::sort(ts.begin(), ts.end());
  *best = ts.front();
  return ts[ts.size() / 2];
}

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s MODEL.txt [N] [repeats]\n", argv[0]);
    return 2;
  }
  const int n = argc > 2 ? std::atoi(argv[2]) : 100000;
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 7;
  std::ifstream in(argv[1]);
  double g0;
  if (!(in >> g0)) { std::fprintf(stderr, "cannot read %s\n", argv[1]); return 2; }
  pinocchio::Model model;
  int parent;
  while (in >> parent) {
    Eigen::Matrix3d R, I;
    Eigen::Vector3d p, c;
    double m;
    for (int i = 0; i < 9; ++i) in >> R(i / 3, i % 3);
    for (int i = 0; i < 3; ++i) in >> p(i);
    in >> m;
    for (int i = 0; i < 3; ++i) in >> c(i);
    for (int i = 0; i < 9; ++i) in >> I(i / 3, i % 3);
    const auto id = model.addJoint(parent, pinocchio::JointModelRZ(), pinocchio::SE3(R, p),
                                   "joint" + std::to_string(model.njoints));
    model.appendBodyToJoint(id, pinocchio::Inertia(m, c, I));
  }
  model.gravity.linear(Eigen::Vector3d(0, 0, -g0));
  pinocchio::Data data(model);

  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> uq(-3.141592653589793, 3.141592653589793), uv(-5, 5), ua(-20, 20),
      uu(-200, 200);
  std::vector<Eigen::VectorXd> Q(n), V(n), A(n), U(n);
  for (int i = 0; i < n; ++i) {
    Q[i].resize(model.nq); V[i].resize(model.nv); A[i].resize(model.nv); U[i].resize(model.nv);
    for (int j = 0; j < model.nv; ++j) { Q[i][j] = uq(rng); V[i][j] = uv(rng); A[i][j] = ua(rng); U[i][j] = uu(rng); }
  }
  volatile double sink = 0;
  double b_rnea, b_aba, b_crba;
  const double t_rnea = per_call([&] {
    double s = 0;
    for (int i = 0; i < n; ++i) s += pinocchio::rnea(model, data, Q[i], V[i], A[i])[1];
    sink = sink + s;
  }, n, repeats, &b_rnea);
  const double t_aba = per_call([&] {
    double s = 0;
    for (int i = 0; i < n; ++i) s += pinocchio::aba(model, data, Q[i], V[i], U[i])[1];
    sink = sink + s;
  }, n, repeats, &b_aba);
  const double t_crba = per_call([&] {
    double s = 0;
    for (int i = 0; i < n; ++i) s += pinocchio::crba(model, data, Q[i])(0, 1);
    sink = sink + s;
  }, n, repeats, &b_crba);
  Eigen::VectorXd q0(3), v0(3), a0(3);
  q0 << 0.3, -0.7, 1.1; v0 << 0.5, -1.5, 2.0; a0 << -3.0, 4.0, 1.0;
  const Eigen::VectorXd tau0 = pinocchio::rnea(model, data, q0, v0, a0);
  std::printf("{\"n\": %d, \"repeats\": %d, \"rnea_median_s\": %.6e, \"rnea_min_s\": %.6e, "
              "\"aba_median_s\": %.6e, \"aba_min_s\": %.6e, \"crba_median_s\": %.6e, \"crba_min_s\": %.6e, "
              "\"tau_check\": [%.17g, %.17g, %.17g]}\n",
              n, repeats, t_rnea, b_rnea, t_aba, b_aba, t_crba, b_crba, tau0[0], tau0[1], tau0[2]);
  return 0;
}
