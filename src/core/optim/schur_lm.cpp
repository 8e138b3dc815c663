#include "schur_lm.h"

#include <ceres/loss_function.h>

#include <Eigen/Cholesky>
#include <Eigen/CholmodSupport>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_map>

namespace binloop::optim_detail {
namespace {

using Mat66 = Eigen::Matrix<double, 6, 6>;
using Mat63 = Eigen::Matrix<double, 6, 3>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// Ceres's defaults (Solver::Options), so that the stopping rules stay what they were.
constexpr double kFunctionTolerance = 1e-6, kGradientTolerance = 1e-10, kParameterTolerance = 1e-8;
constexpr double kMinRelativeDecrease = 1e-3;
constexpr double kInitialMu = 1e-4, kMinMu = 1e-16, kMaxMu = 1e32;
constexpr double kMinDiagonal = 1e-6, kMaxDiagonal = 1e32;

// The first row of keyframe block c in the reduced system.
Eigen::Index firstRow(int c) { return Eigen::Index{6} * c; }

double clampedDiagonal(double d) { return std::clamp(d, kMinDiagonal, kMaxDiagonal); }

/// rho(s) (index 0) and rho'(s) (index 1) of the term's loss on chi2 s; no loss: plain squares, rho(s) = s.
void robustLoss(const ceres::LossFunction* loss, double s, double rho[3]) {
  if (loss) {
    loss->Evaluate(s, rho);
    return;
  }
  rho[0] = s;
  rho[1] = 1;
  rho[2] = 0;
}

// ceres::HuberLoss(delta), the pose optimiser's robust kernel, one per distinct width among a run's terms
// (a stage has two: mono and stereo), made once per run rather than per term and evaluation.
class Losses {
 public:
  Losses(const std::vector<BaTerm>& terms, const std::vector<uint32_t>& used, bool robust) {
    if (!robust) return;
    of_term_.reserve(used.size());
    for (uint32_t i : used) {
      const double delta = terms[i].huber_delta;
      if (!(delta > 0)) {  // no width: plain squares for this term
        of_term_.push_back(nullptr);
        continue;
      }
      auto it = std::find_if(losses_.begin(), losses_.end(), [&](const auto& l) { return l.first == delta; });
      if (it == losses_.end()) {
        losses_.emplace_back(delta, std::make_unique<ceres::HuberLoss>(delta));
        it = losses_.end() - 1;
      }
      of_term_.push_back(it->second.get());
    }
  }
  /// The loss of the term at position `pos` in the run's used terms; nullptr: plain squares.
  const ceres::LossFunction* at(size_t pos) const { return of_term_.empty() ? nullptr : of_term_[pos]; }

 private:
  std::vector<std::pair<double, std::unique_ptr<ceres::HuberLoss>>> losses_;
  std::vector<const ceres::LossFunction*> of_term_;
};

// What does not change during a run: which terms, keyframes and points take part, and where each
// keyframe pair lands in the reduced camera system.
struct Structure {
  std::vector<uint32_t> used;  // term indices, ascending
  std::vector<int> col;        // per keyframe: its block column in the reduced system; -1: fixed or unseen
  std::vector<int> term_col;   // per position in `used`: its keyframe's column
  int num_free = 0;
  std::vector<uint32_t> points;             // point indices seen by a used term, ascending
  std::vector<uint32_t> point_begin;        // per point slot: its range in point_terms
  std::vector<uint32_t> point_free;         // per point slot: where its free-keyframe terms start
  std::vector<uint32_t> point_terms;        // positions in `used`; fixed keyframes' first, then by column
  std::vector<std::pair<int, int>> blocks;  // upper blocks (a <= b) of the reduced system; block c = (c, c)
  std::vector<uint32_t> pair_block;         // per point, per pair a <= b of its free terms: the block
};

Structure makeStructure(const std::vector<BaTerm>& terms, const std::vector<bool>& use,
                        const std::vector<bool>& fixed, size_t num_points) {
  Structure st;
  st.col.assign(fixed.size(), -1);
  std::vector<int> point_slot(num_points, -1);
  std::vector<bool> kf_seen(fixed.size());
  for (uint32_t i = 0; i < terms.size(); ++i) {
    if (!use[i]) continue;
    st.used.push_back(i);
    kf_seen[terms[i].keyframe] = true;
    point_slot[terms[i].point] = 0;
  }
  for (size_t k = 0; k < fixed.size(); ++k)
    if (kf_seen[k] && !fixed[k]) st.col[k] = st.num_free++;
  for (uint32_t i : st.used) st.term_col.push_back(st.col[terms[i].keyframe]);
  for (size_t j = 0; j < num_points; ++j) {
    if (point_slot[j] < 0) continue;
    point_slot[j] = static_cast<int>(st.points.size());
    st.points.push_back(static_cast<uint32_t>(j));
  }
  std::vector<uint32_t> count(st.points.size() + 1, 0);
  for (uint32_t u : st.used) ++count[point_slot[terms[u].point] + 1];
  for (size_t s = 0; s < st.points.size(); ++s) count[s + 1] += count[s];
  st.point_begin = count;
  st.point_terms.resize(st.used.size());
  for (uint32_t pos = 0; pos < st.used.size(); ++pos)
    st.point_terms[count[point_slot[terms[st.used[pos]].point]]++] = pos;

  for (int c = 0; c < st.num_free; ++c) st.blocks.emplace_back(c, c);
  std::unordered_map<uint64_t, uint32_t> block_of;
  const auto colOf = [&](uint32_t pos) { return st.term_col[pos]; };
  st.point_free.resize(st.points.size());
  for (size_t s = 0; s < st.points.size(); ++s) {
    const auto b = st.point_terms.begin() + st.point_begin[s],
               e = st.point_terms.begin() + st.point_begin[s + 1];
    std::stable_sort(b, e, [&](uint32_t x, uint32_t y) { return colOf(x) < colOf(y); });
    auto f = b;
    while (f != e && colOf(*f) < 0) ++f;
    st.point_free[s] = static_cast<uint32_t>(f - st.point_terms.begin());
    for (auto a = f; a != e; ++a) {
      for (auto c = a; c != e; ++c) {
        const int ca = colOf(*a), cb = colOf(*c);
        if (ca == cb) {
          st.pair_block.push_back(static_cast<uint32_t>(ca));
          continue;
        }
        const uint64_t key = static_cast<uint64_t>(ca) * st.num_free + cb;
        auto it = block_of.find(key);
        if (it == block_of.end()) {
          it = block_of.emplace(key, static_cast<uint32_t>(st.blocks.size())).first;
          st.blocks.emplace_back(ca, cb);
        }
        st.pair_block.push_back(it->second);
      }
    }
  }
  return st;
}

// The normal equations at one state: H = sum w J^T J and g = sum w J^T r, split into the keyframe blocks
// (U, gc), the point blocks (V, gp) and the keyframe-point blocks (W, one per term).
struct Linear {
  double cost = 0;  // 1/2 sum rho(chi2)
  double gradient_max = 0;
  std::vector<Mat66> U;
  std::vector<Vec6> gc;
  std::vector<Eigen::Matrix3d> V;
  std::vector<Eigen::Vector3d> gp;
  std::vector<Mat63> W;  // per used term; unused for a fixed keyframe's
};

class Solver {
 public:
  Solver(const ProjectionConstants& k, const std::vector<BaTerm>& terms, const Structure& st,
         const LmRun& run)
      : k_(k), terms_(terms), st_(st), run_(run), losses_(terms, st.used, run.robust) {
    lin_.U.resize(st.num_free);
    lin_.gc.resize(st.num_free);
    lin_.V.resize(st.points.size());
    lin_.gp.resize(st.points.size());
    lin_.W.resize(st.used.size());
    Y_.resize(st.used.size());
    V_inv_.resize(st.points.size());
    blocks_.resize(st.blocks.size());
    dc_.resize(st.num_free);
    dp_.resize(st.points.size());
  }

  void linearize(const BaState& s) {
    Linear& l = lin_;
    l.cost = 0;
    std::fill(l.U.begin(), l.U.end(), Mat66::Zero());
    std::fill(l.gc.begin(), l.gc.end(), Vec6::Zero());
    for (size_t slot = 0; slot < st_.points.size(); ++slot) {
      Eigen::Matrix3d V = Eigen::Matrix3d::Zero();
      Eigen::Vector3d gp = Eigen::Vector3d::Zero();
      for (uint32_t i = st_.point_begin[slot]; i < st_.point_begin[slot + 1]; ++i) {
        const uint32_t pos = st_.point_terms[i];
        const BaTerm& t = terms_[st_.used[pos]];
        const LinearizedReprojection e = evaluateTerm(k_, t, s, true);
        double rho[3];
        robustLoss(losses_.at(pos), e.chi2, rho);
        l.cost += 0.5 * rho[0];
        const Eigen::Matrix3d wJp = rho[1] * e.J_point;
        V.noalias() += e.J_point.transpose() * wJp;
        gp.noalias() += wJp.transpose() * e.r;
        const int c = st_.term_col[pos];
        if (c < 0) continue;
        const Eigen::Matrix<double, 3, 6> wJc = rho[1] * e.J_pose;
        l.U[c].noalias() += e.J_pose.transpose() * wJc;
        l.gc[c].noalias() += wJc.transpose() * e.r;
        l.W[pos].noalias() = wJc.transpose() * e.J_point;
      }
      l.V[slot] = V;
      l.gp[slot] = gp;
    }
    l.gradient_max = 0;
    for (const Vec6& g : l.gc) l.gradient_max = std::max(l.gradient_max, g.cwiseAbs().maxCoeff());
    for (const Eigen::Vector3d& g : l.gp) l.gradient_max = std::max(l.gradient_max, g.cwiseAbs().maxCoeff());
  }

  const Linear& linear() const { return lin_; }

  /// Solves the damped normal equations; false when the reduced system is not positive definite or the
  /// step is not finite. Sets the step and what the linear model promises it gains.
  bool solve(double mu) {
    const Linear& l = lin_;
    const int nf = st_.num_free;
    std::fill(blocks_.begin(), blocks_.end(), Mat66::Zero());
    Eigen::VectorXd rhs(firstRow(nf));
    for (int c = 0; c < nf; ++c) rhs.segment<6>(firstRow(c)) = -l.gc[c];
    size_t pair = 0;
    for (size_t slot = 0; slot < st_.points.size(); ++slot) {
      Eigen::Matrix3d V = l.V[slot];
      for (int i = 0; i < 3; ++i) V(i, i) += mu * clampedDiagonal(l.V[slot](i, i));
      const Eigen::Matrix3d V_inv = V.inverse();
      if (!V_inv.allFinite()) return false;
      V_inv_[slot] = V_inv;
      const uint32_t end = st_.point_begin[slot + 1];
      for (uint32_t a = st_.point_free[slot]; a < end; ++a) {
        const uint32_t pa = st_.point_terms[a];
        Y_[pa].noalias() = l.W[pa] * V_inv;
        const int ca = st_.term_col[pa];
        rhs.segment<6>(firstRow(ca)).noalias() += Y_[pa] * l.gp[slot];
        for (uint32_t b = a; b < end; ++b) {
          const uint32_t pb = st_.point_terms[b];
          Mat66 M = Y_[pa] * l.W[pb].transpose();
          // Two terms of one point in one keyframe: the block gets both cross products.
          if (b != a && st_.term_col[pb] == ca) M += M.transpose().eval();
          blocks_[st_.pair_block[pair++]] -= M;
        }
      }
    }
    for (int c = 0; c < nf; ++c) {
      blocks_[c] += l.U[c];
      for (int i = 0; i < 6; ++i) blocks_[c](i, i) += mu * clampedDiagonal(l.U[c](i, i));
    }
    Eigen::VectorXd x;
    if (nf > 0 && !solveReduced(rhs, x)) return false;
    for (int c = 0; c < nf; ++c) dc_[c] = x.segment<6>(firstRow(c));
    for (size_t slot = 0; slot < st_.points.size(); ++slot) {
      Eigen::Vector3d b = -l.gp[slot];
      for (uint32_t i = st_.point_free[slot]; i < st_.point_begin[slot + 1]; ++i) {
        const uint32_t pos = st_.point_terms[i];
        b.noalias() -= l.W[pos].transpose() * dc_[st_.term_col[pos]];
      }
      dp_[slot] = V_inv_[slot] * b;
    }
    // The linear model's gain: -g.dx - 1/2 dx.H.dx = 1/2 (mu dx.D.dx - g.dx), since (H + mu D) dx = -g.
    double gain = 0, step2 = 0;
    for (int c = 0; c < nf; ++c) {
      for (int i = 0; i < 6; ++i) {
        const double d = dc_[c](i);
        gain += mu * clampedDiagonal(l.U[c](i, i)) * d * d - l.gc[c](i) * d;
      }
      step2 += dc_[c].squaredNorm();
    }
    for (size_t slot = 0; slot < st_.points.size(); ++slot) {
      for (int i = 0; i < 3; ++i) {
        const double d = dp_[slot](i);
        gain += mu * clampedDiagonal(l.V[slot](i, i)) * d * d - l.gp[slot](i) * d;
      }
      step2 += dp_[slot].squaredNorm();
    }
    model_gain_ = 0.5 * gain;
    step_norm_ = std::sqrt(step2);
    return std::isfinite(model_gain_) && std::isfinite(step_norm_);
  }

  double modelGain() const { return model_gain_; }
  double stepNorm() const { return step_norm_; }

  /// `to` = `from` moved by the last step (only the free keyframes and the used points are written).
  void apply(const BaState& from, BaState& to) const {
    for (size_t k = 0; k < st_.col.size(); ++k)
      if (st_.col[k] >= 0) to.T[k] = poseFromIncrement(dc_[st_.col[k]].data(), from.T[k]);
    for (size_t slot = 0; slot < st_.points.size(); ++slot)
      to.p[st_.points[slot]] = from.p[st_.points[slot]] + dp_[slot];
  }

  /// 1/2 sum rho(chi2) at a state; false when an observed point is at or behind its camera there.
  bool cost(const BaState& s, double* out) const {
    double sum = 0;
    for (size_t pos = 0; pos < st_.used.size(); ++pos) {
      const LinearizedReprojection e = evaluateTerm(k_, terms_[st_.used[pos]], s, false);
      if (!e.in_front || !std::isfinite(e.chi2)) return false;
      double rho[3];
      robustLoss(losses_.at(pos), e.chi2, rho);
      sum += 0.5 * rho[0];
    }
    *out = sum;
    return true;
  }

  /// The norm of the variables that move, for the step-size stopping rule.
  double variableNorm(const BaState& s) const {
    double n2 = 0;
    for (size_t k = 0; k < st_.col.size(); ++k)
      if (st_.col[k] >= 0) n2 += s.T[k].translation().squaredNorm();
    for (uint32_t j : st_.points) n2 += s.p[j].squaredNorm();
    return std::sqrt(n2);
  }

 private:
  bool solveReduced(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
    const Eigen::Index n = firstRow(st_.num_free);
    if (run_.solver == BaLinearSolver::kDenseSchur) {
      Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
      for (size_t b = 0; b < blocks_.size(); ++b)
        S.block<6, 6>(firstRow(st_.blocks[b].first), firstRow(st_.blocks[b].second)) = blocks_[b];
      const Eigen::LLT<Eigen::MatrixXd, Eigen::Upper> llt(S);
      if (llt.info() != Eigen::Success) return false;
      x = llt.solve(rhs);
    } else {
      // The pattern is the same at every step of a run: build it and order it once, then only write values.
      if (S_.rows() != n) {
        makeSparsePattern(n);
        llt_.cholmod().print = 0;  // a matrix that is not positive definite is a rejected step, not a message
        llt_.analyzePattern(S_);
      }
      double* values = S_.valuePtr();
      for (size_t b = 0; b < blocks_.size(); ++b) {
        const bool diagonal = st_.blocks[b].first == st_.blocks[b].second;
        for (int j = 0; j < 6; ++j) {
          double* column = values + block_offset_[b][j];
          for (int i = 0; i <= (diagonal ? j : 5); ++i) column[i] = blocks_[b](i, j);
        }
      }
      llt_.factorize(S_);
      if (llt_.info() != Eigen::Success) return false;
      x = llt_.solve(rhs);
    }
    return x.allFinite();
  }

  // The upper triangle of the reduced system's block pattern, and where each block's column j starts in
  // the value array: in column-major storage a block's rows are contiguous within each of its columns.
  void makeSparsePattern(Eigen::Index n) {
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(36 * blocks_.size());
    for (const auto& [ca, cb] : st_.blocks) {
      for (int j = 0; j < 6; ++j) {
        for (int i = 0; i <= (ca == cb ? j : 5); ++i)
          entries.emplace_back(firstRow(ca) + i, firstRow(cb) + j, 0.0);
      }
    }
    S_.resize(n, n);
    S_.setFromTriplets(entries.begin(), entries.end());
    S_.makeCompressed();
    block_offset_.resize(st_.blocks.size());
    const int* rows = S_.innerIndexPtr();
    for (size_t b = 0; b < st_.blocks.size(); ++b) {
      const auto [ca, cb] = st_.blocks[b];
      for (int j = 0; j < 6; ++j) {
        const Eigen::Index col = firstRow(cb) + j;
        const int* first =
            std::lower_bound(rows + S_.outerIndexPtr()[col], rows + S_.outerIndexPtr()[col + 1],
                             static_cast<int>(firstRow(ca)));
        block_offset_[b][j] = first - rows;
      }
    }
  }

  const ProjectionConstants& k_;
  const std::vector<BaTerm>& terms_;
  const Structure& st_;
  const LmRun& run_;
  const Losses losses_;
  Linear lin_;
  std::vector<Mat63> Y_;  // per used term of a free keyframe: W V^-1
  std::vector<Eigen::Matrix3d> V_inv_;
  std::vector<Mat66> blocks_;
  std::vector<Vec6> dc_;
  std::vector<Eigen::Vector3d> dp_;
  double model_gain_ = 0, step_norm_ = 0;
  // The sparse path's. Supernodal: far points tie each keyframe to dozens of others, so the factor is
  // dense in bands, where CHOLMOD's dense kernels beat a simplicial (one column at a time) factorisation.
  Eigen::SparseMatrix<double> S_;
  std::vector<std::array<std::ptrdiff_t, 6>> block_offset_;  // per block, per column: its first value
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Upper> llt_;
};

}  // namespace

LinearizedReprojection evaluateTerm(const ProjectionConstants& k, const BaTerm& term, const BaState& s,
                                    bool with_jacobians) {
  return linearizeReprojection(k, s.T[term.keyframe], s.p[term.point], term.obs, term.sqrt_info, term.stereo,
                               with_jacobians);
}

LmOutcome solveSchurLm(const ProjectionConstants& k, const std::vector<BaTerm>& terms,
                       const std::vector<bool>& use, const std::vector<bool>& fixed, const LmRun& run,
                       BaState& state) {
  LmOutcome out;
  const Structure st = makeStructure(terms, use, fixed, state.p.size());
  if (st.used.empty()) return out;
  const auto aborted = [&] { return run.abort && run.abort->load(); };

  Solver solver(k, terms, st, run);
  solver.linearize(state);
  // Ceres reads the abort flag after evaluating the start too (its iteration 0).
  if (aborted()) {
    out.aborted = true;
    return out;
  }
  if (solver.linear().gradient_max <= kGradientTolerance) return out;
  BaState trial = state;
  double mu = kInitialMu, nu = 2;
  // Ceres's order: a step too small to matter, or one that changes the cost by less than the function
  // tolerance, ends the run without being taken or counted.
  while (out.iterations < run.max_iterations) {
    bool accepted = false;
    double rho = 0, new_cost = std::numeric_limits<double>::infinity();
    if (solver.solve(mu)) {
      if (solver.stepNorm() <= kParameterTolerance * (solver.variableNorm(state) + kParameterTolerance))
        break;
      solver.apply(state, trial);
      if (solver.cost(trial, &new_cost)) {
        if (std::abs(solver.linear().cost - new_cost) <= kFunctionTolerance * solver.linear().cost) break;
        rho = (solver.linear().cost - new_cost) / solver.modelGain();
        accepted = solver.modelGain() > 0 && rho > kMinRelativeDecrease;
      }
    }
    ++out.iterations;
    bool converged = false;
    if (accepted) {
      std::swap(state, trial);
      const double f = 2 * rho - 1;
      mu = std::max(kMinMu, mu * std::max(1.0 / 3.0, 1.0 - f * f * f));
      nu = 2;
      solver.linearize(state);
      converged = solver.linear().gradient_max <= kGradientTolerance;
    } else {
      mu *= nu;
      nu *= 2;
      converged = mu > kMaxMu;
    }
    if (aborted()) {
      out.aborted = true;
      break;
    }
    if (converged) break;
  }
  return out;
}

}  // namespace binloop::optim_detail
