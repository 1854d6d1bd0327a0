// Pinocchio's own C++ cost of rnea / aba / crba on any fixed-base arm of 1-DoF joints, for
// `benchmarks/cpp_pinocchio.py`.
//
// Usage: pin_cpp_bench MODEL.txt STATES.bin N REPEATS OUT.bin
//
// MODEL.txt (written by cpp_pinocchio.py from the Python pinocchio.Model, so that the C++ model is
// the very model -- reduced, continuous joints made revolute -- that Python and the generated
// kernels use): first line "gx gy gz" (model.gravity.linear), then one line per joint, in order:
//   TYPE parent ax ay az  R(9, row-major) p(3)  mass com(3) inertia-about-the-com(9, row-major)
// TYPE is RX RY RZ PX PY PZ (Pinocchio's axis-aligned joints, the axis columns are ignored) or
// RU PU (JointModelRevoluteUnaligned / JointModelPrismaticUnaligned about the unit axis a);
// parent is Pinocchio's joint index (0 = universe); (R, p) the joint placement in the parent's
// frame (model.jointPlacements), (mass, com, inertia) the body inertia (model.inertias).
//
// STATES.bin: N x nv float64 row-major arrays Q, V, A, U, one after the other.
// OUT.bin (written): tau = rnea(Q, V, A) (N x nv), qdd = aba(Q, V, U) (N x nv), then crba(Q) of the
// first min(N, 100) states (nv x nv row-major, upper triangle as Pinocchio fills it), for the
// caller's cross-check against pinocchio from Python.
// Prints one JSON line: median and min seconds per call over REPEATS timed passes over the N
// states (after one warm-up pass).
//
// Every algorithm is called with Eigen::Ref<const Eigen::VectorXd> arguments, the types
// libpinocchio_default instantiates (and the Python bindings call): with
// -DPINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION the calls resolve to the precompiled library; without
// it the same templates are compiled into this program.
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/crba.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

using Clock = std::chrono::steady_clock;
using Vec = Eigen::VectorXd;
using CRef = Eigen::Ref<const Vec>;

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

static int fail(const std::string& msg) {
  std::fprintf(stderr, "pin_cpp_bench: %s\n", msg.c_str());
  return 2;
}

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: %s MODEL.txt STATES.bin N REPEATS OUT.bin\n", argv[0]);
    return 2;
  }
  const int n = std::atoi(argv[3]);
  const int repeats = std::atoi(argv[4]);
  if (n < 1 || repeats < 1) return fail("N and REPEATS must be >= 1");

  std::ifstream in(argv[1]);
  Eigen::Vector3d g;
  if (!(in >> g[0] >> g[1] >> g[2])) return fail(std::string("cannot read gravity from ") + argv[1]);
  pinocchio::Model model;
  std::string type;
  while (in >> type) {
    int parent;
    Eigen::Vector3d axis, p, c;
    Eigen::Matrix3d R, I;
    double m;
    in >> parent;
    for (int i = 0; i < 3; ++i) in >> axis(i);
    for (int i = 0; i < 9; ++i) in >> R(i / 3, i % 3);
    for (int i = 0; i < 3; ++i) in >> p(i);
    in >> m;
    for (int i = 0; i < 3; ++i) in >> c(i);
    for (int i = 0; i < 9; ++i) in >> I(i / 3, i % 3);
    if (!in) return fail(std::string("malformed joint line in ") + argv[1]);
    if (parent < 0 || parent >= model.njoints) return fail("joint parent out of range");
    const pinocchio::SE3 placement(R, p);
    const std::string name = "joint" + std::to_string(model.njoints);
    pinocchio::JointIndex id;
    if (type == "RX") id = model.addJoint(parent, pinocchio::JointModelRX(), placement, name);
    else if (type == "RY") id = model.addJoint(parent, pinocchio::JointModelRY(), placement, name);
    else if (type == "RZ") id = model.addJoint(parent, pinocchio::JointModelRZ(), placement, name);
    else if (type == "PX") id = model.addJoint(parent, pinocchio::JointModelPX(), placement, name);
    else if (type == "PY") id = model.addJoint(parent, pinocchio::JointModelPY(), placement, name);
    else if (type == "PZ") id = model.addJoint(parent, pinocchio::JointModelPZ(), placement, name);
    else if (type == "RU") id = model.addJoint(parent, pinocchio::JointModelRevoluteUnaligned(axis), placement, name);
    else if (type == "PU") id = model.addJoint(parent, pinocchio::JointModelPrismaticUnaligned(axis), placement, name);
    else return fail("unknown joint type '" + type + "'");
    model.appendBodyToJoint(id, pinocchio::Inertia(m, c, I));
  }
  if (model.nv < 1) return fail("no joint in the model file");
  model.gravity.linear(g);
  model.gravity.angular().setZero();
  pinocchio::Data data(model);
  const int nv = model.nv;

  const size_t block = size_t(n) * nv;
  std::vector<double> S(4 * block);
  {
    std::ifstream sf(argv[2], std::ios::binary);
    sf.read(reinterpret_cast<char*>(S.data()), std::streamsize(S.size() * sizeof(double)));
    if (!sf || sf.gcount() != std::streamsize(S.size() * sizeof(double)))
      return fail(std::string("cannot read ") + std::to_string(4 * block) + " doubles from " + argv[2]);
  }
  const double *Q = S.data(), *V = Q + block, *A = V + block, *U = A + block;
  auto row = [nv](const double* X, int i) { return Eigen::Map<const Vec>(X + size_t(i) * nv, nv); };
  std::vector<double> TAU(block), QDD(block);

  volatile double sink = 0;
  double b_rnea, b_aba, b_crba;
  const double t_rnea = per_call([&] {
    for (int i = 0; i < n; ++i) {
      const Vec& tau = pinocchio::rnea(model, data, CRef(row(Q, i)), CRef(row(V, i)), CRef(row(A, i)));
      std::copy(tau.data(), tau.data() + nv, TAU.data() + size_t(i) * nv);
    }
  }, n, repeats, &b_rnea);
  const double t_aba = per_call([&] {
    for (int i = 0; i < n; ++i) {
      const Vec& qdd = pinocchio::aba(model, data, CRef(row(Q, i)), CRef(row(V, i)), CRef(row(U, i)),
                                      pinocchio::Convention::LOCAL);
      std::copy(qdd.data(), qdd.data() + nv, QDD.data() + size_t(i) * nv);
    }
  }, n, repeats, &b_aba);
  const double t_crba = per_call([&] {
    double s = 0;
    for (int i = 0; i < n; ++i) s += pinocchio::crba(model, data, CRef(row(Q, i)), pinocchio::Convention::LOCAL)(0, nv - 1);
    sink = sink + s;
  }, n, repeats, &b_crba);

  const int k = std::min(n, 100);
  std::vector<double> MM(size_t(k) * nv * nv);
  for (int i = 0; i < k; ++i) {
    const Eigen::MatrixXd& M = pinocchio::crba(model, data, CRef(row(Q, i)), pinocchio::Convention::LOCAL);
    for (int r = 0; r < nv; ++r)
      for (int c = 0; c < nv; ++c) MM[(size_t(i) * nv + r) * nv + c] = M(r, c);
  }
  {
    std::ofstream of(argv[5], std::ios::binary);
    of.write(reinterpret_cast<const char*>(TAU.data()), std::streamsize(block * sizeof(double)));
    of.write(reinterpret_cast<const char*>(QDD.data()), std::streamsize(block * sizeof(double)));
    of.write(reinterpret_cast<const char*>(MM.data()), std::streamsize(MM.size() * sizeof(double)));
    if (!of) return fail(std::string("cannot write ") + argv[5]);
  }
  std::printf("{\"n\": %d, \"repeats\": %d, \"nv\": %d, \"njoints\": %d, \"crba_checked\": %d, "
              "\"rnea_median_s\": %.6e, \"rnea_min_s\": %.6e, \"aba_median_s\": %.6e, \"aba_min_s\": %.6e, "
              "\"crba_median_s\": %.6e, \"crba_min_s\": %.6e}\n",
              n, repeats, nv, int(model.njoints), k, t_rnea, b_rnea, t_aba, b_aba, t_crba, b_crba);
  return 0;
}
