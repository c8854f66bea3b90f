// SPDX-License-Identifier: BSD-3-Clause
// The miss budget covers the whole frame's caching, not only its wait for loads: what follows the
// wait (the frame's thread getting a core back, placing stand-ins, building the frame's view) is
// its tail, and the wait ends that much before the budget runs out. The tail is estimated from the
// frames before: the largest tail seen, decaying by kDecay a frame (one slow frame does not cost
// the next ten their waits), and never more than kMaxShare of the budget (a frame always waits for
// some of its loads).
#pragma once

#include <algorithm>

namespace afam {

class TailReserve {
 public:
  static constexpr double kDecay = 0.9;
  static constexpr double kMaxShare = 0.5;
  static constexpr double kMaxBudgetMs = 1e9;  ///< longer budgets wait this long

  /// How long a frame with `budgetMs` waits for its loads (ms, >= 0).
  double waitMs(double budgetMs) const {
    const double budget = std::min(std::max(budgetMs, 0.0), kMaxBudgetMs);
    return budget - std::min(reserveMs_, budget * kMaxShare);
  }
  /// A budgeted frame's tail: milliseconds from the end of its wait to the end of its caching.
  void observe(double tailMs) { reserveMs_ = std::max(std::max(tailMs, 0.0), reserveMs_ * kDecay); }
  double reserveMs() const { return reserveMs_; }

 private:
  double reserveMs_ = 0;
};

}  // namespace afam
