// Where sampling routines get their random numbers from. Sampling routines take uniforms,
// never an RNG (STYLE.md): a warp takes a Vec2; an estimator technique takes a Uniforms&,
// which may be backed by an RNG stream, by a fixed array (tests, inversion round trips), or
// by the primary-sample-space state of an MCMC chain.
#pragma once

#include <span>
#include <stdexcept>
#include <vector>

#include "lib/core/rng.h"

namespace tb {

class Uniforms {
 public:
  virtual ~Uniforms() = default;
  virtual double next() = 0;
  Vec2 next2() {
    const double a = next();
    return {a, next()};
  }
};

class RngUniforms final : public Uniforms {
 public:
  explicit RngUniforms(Rng& rng) : rng_(&rng) {}
  double next() override { return rng_->uniform(); }

 private:
  Rng* rng_;
};

// Replays a fixed list of uniforms; running past its end is a programming error.
class FixedUniforms final : public Uniforms {
 public:
  explicit FixedUniforms(std::span<const double> u) : u_(u.begin(), u.end()) {}
  FixedUniforms(std::initializer_list<double> u) : u_(u) {}
  double next() override {
    if (i_ >= u_.size()) throw std::out_of_range("FixedUniforms: more uniforms requested than supplied");
    return u_[i_++];
  }
  size_t consumed() const { return i_; }

 private:
  std::vector<double> u_;
  size_t i_ = 0;
};

}  // namespace tb
