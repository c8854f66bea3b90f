// SPDX-License-Identifier: BSD-3-Clause
// A small micro-model with random control points in [-1, 1], for the evaluation tests.
#pragma once

#include <random>
#include <vector>

#include "afam/spline/evaluate.hpp"

struct SmallModel {
  std::vector<float> control;
  afam::ModelView view;
  SmallModel(int nx, int ny, int nz, int px, int py, int pz, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uni(-1.f, 1.f);
    control.resize(size_t(nx) * ny * nz);
    for (auto& x : control) x = uni(rng);
    view.knots[0] = afam::Knots::make(nx, px);
    view.knots[1] = afam::Knots::make(ny, py);
    view.knots[2] = afam::Knots::make(nz, pz);
    view.control = control.data();
  }
};
