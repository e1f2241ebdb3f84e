// The primary-sample-space state of a Metropolis chain (Kelemen, Szirmay-Kalos, Antal & Csonka
// 2002, "A Simple and Robust Mutation Strategy for the Metropolis Light Transport Algorithm"):
// the uniforms u in [0,1)^inf that a Monte Carlo sample function consumes, mutated instead of
// drawn afresh. The state implements Uniforms (lib/core/uniforms.h), so the same sampling code
// (generate_camera_subpath, connect_bdpt, ...) runs on an RNG stream, a fixed array or a chain.
//
// Streams. Uniforms are organised in kStreams interleaved streams (camera, light, connection;
// pbrt-v3 Sec. 16.4.4, MLTSampler): uniform i of stream s is coordinate i * kStreams + s of the
// state, so a camera subpath that grows by one vertex does not shift the light subpath's numbers.
// use_stream(s) switches stream and keeps each stream's read position; restart() rewinds all.
//
// Mutations (Kelemen et al. 2002, Sec. 3 and 4):
//   large step: every coordinate replaced by a fresh uniform; T(x -> y) = 1 on [0,1)^n.
//   small step: y_i = x_i + sigma z_i (mod 1), z_i ~ N(0,1) independent: the wrapped Gaussian
//     T(x -> y) = prod_i g_sigma(y_i - x_i),  g_sigma(d) = sum_{m in Z} phi_sigma(d + m),
//     which is symmetric, T(x -> y) = T(y -> x), since phi is even. (Kelemen's exponential
//     perturbation is symmetric too; the Gaussian is used, as in pbrt-v3, because n small steps
//     compose into one of sigma sqrt(n), which makes lazy updates exact in distribution.)
//
// Lazy updates (Kelemen et al. 2002, Sec. 5.1; pbrt-v3 Sec. 16.4.4): a coordinate is only brought
// up to date when it is read. Each coordinate remembers the iteration it was last modified at;
// reading it at iteration n after a gap applies, in order, (1) a fresh uniform if an accepted
// large step happened in the gap, (2) the n_small accepted small steps of the gap at once as one
// wrapped Gaussian of sigma sqrt(n_small), then (3) the current iteration's mutation. A rejected
// iteration restores every coordinate modified in it and does not count as an iteration, so the
// gap counts accepted iterations only, exactly as an eagerly updated state would.
//
// Rescaled small step (Szirmay-Kalos & Szecsi 2017 as described by Zirr & Dachsbacher 2020,
// Sec. 8: an isotropic step whose sigma depends on the current path; docs/mlt-pss.md, "Step
// rescaling"). With set_rescaled(true), a small step perturbs by sigma(x) (passed to
// start_iteration) exactly the coordinates read by the current state x AND by the proposal y,
// D(x) ∩ D(y); every other coordinate moves by the fixed sigma (lazily, as above). The set
// D(x) ∩ D(y) is symmetric in (x, y), and whether the proposal reads a coordinate is decided by the
// coordinates it read before, so this is a proper proposal with density
//   T(x -> y) = prod_{i in D(x) ∩ D(y)} g_{sigma(x)}(y_i - x_i) * prod_{i not in it} g_sigma(y_i - x_i)
// and T(y -> x) / T(x -> y) = prod_{i in D(x) ∩ D(y)} g_{sigma(y)}(x_i - y_i) / g_{sigma(x)}(y_i - x_i)
// (the fixed-sigma factors, over infinitely many coordinates, cancel pairwise): RescaledSmallStep::log_reverse_over_forward (pss_steps.h).
// D(x) is a prefix of each stream (commit_reads / accept record how far x read each stream).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "lib/core/rng.h"
#include "lib/core/uniforms.h"

namespace tb::pss {

enum Stream : int { kCameraStream = 0, kLightStream = 1, kConnectionStream = 2 };
inline constexpr int kStreams = 3;

// Uniforms organised in streams (see the top of this file).
class StreamUniforms : public Uniforms {
 public:
  virtual void use_stream(int stream) = 0;  // continue reading stream `stream`
  virtual void restart() = 0;               // every stream back to its first uniform
};

// Wrapped Gaussian density on the circle [0,1): g_sigma(d) = sum_m phi_sigma(d + m), summed over
// the images |m| <= ceil(12 sigma) + 1 (the rest is below 1e-31 of the peak); g(d) = g(-d) bitwise.
double wrapped_normal_pdf(double d, double sigma);
// x reduced to [0, 1): x - floor(x), with 1 (from x = -1e-17) mapped to 0, the same point of the
// circle. Inline, and without the floor call for x in [-1, 2), where every perturbed coordinate of
// a small step lands (|sigma z| < 1); the results are bitwise those of x - floor(x) there.
inline double wrap01(double x) {
  if (x >= 0.0 && x < 1.0) return x;
  if (x >= 1.0 && x < 2.0) return x - 1.0;
  const double r = (x >= -1.0 && x < 0.0) ? x + 1.0 : x - std::floor(x);
  return r < 1.0 ? r : 0.0;
}

// The lazily updated chain state.
class PssState final : public StreamUniforms {
 public:
  // rng: the stream of fresh uniforms and Gaussian perturbations; sigma: the small-step scale.
  PssState(Rng rng, double sigma);
  // The state at a given point u (every coordinate current at iteration 0): the dense form of the
  // mutations (pss_kernel.h) runs the same lazy updates from it.
  static PssState at(const std::vector<double>& u, Rng rng, double sigma);
  // Back to the state of PssState(rng, sigma), keeping the storage (the driver's bootstrap reuses
  // one state per thread instead of allocating one per sample).
  void reset(Rng rng, double sigma);

  // Starts proposing: iteration n + 1 with a large or a small step. Rewinds the streams.
  // sigma_shared: the rescaled small step's sigma(x) for D(x) ∩ D(y) (ignored unless rescaled).
  void start_iteration(bool large_step, double sigma_shared = 0.0);
  // Keeps the proposal (a large step then resets untouched coordinates when they are next read);
  // records the proposal's reads as D(x) of the new current state (commit_reads).
  void accept();
  // Records how far the current state read each stream (its D(x)); call after evaluating the
  // initial state.
  void commit_reads() { current_reads_ = index_; }
  // Rescaled small step (see the top of this file). While proposing y (after evaluating it):
  //   log T(y -> x) / T(x -> y) = sum_{i in D(x) ∩ D(y)} log g_{sigma_y}(x_i - y_i) - log g_{sigma_x}(y_i - x_i).
  // (The ratio itself is the rescaled small step's, pss_steps.h, over PssMove's differences.)
  void set_rescaled(bool on) { rescaled_ = on; }
  bool rescaled() const { return rescaled_; }
  // Coordinates read from each stream since the last restart (the proposal's D(y) once evaluated).
  const std::array<size_t, kStreams>& reads() const { return index_; }
  const std::array<size_t, kStreams>& current_reads() const { return current_reads_; }
  // Restores every coordinate the proposal changed and returns to iteration n.
  void reject();

  // StreamUniforms
  double next() override;
  void use_stream(int stream) override { stream_ = stream; }
  void restart() override { index_.fill(0); }

  // Replaces the generator of fresh numbers (a chain started from a bootstrap sample regenerates
  // that sample with the bootstrap's stream, then mutates with its own).
  void set_rng(const Rng& rng) {
    rng_ = rng;
  }

  // Introspection (tests, checks).
  int64_t iteration() const { return iteration_; }
  bool large_step() const { return large_; }
  size_t coordinates() const { return x_.size(); }
  // Current value of coordinate i, as stored (not brought up to date).
  double stored(size_t i) const { return x_[i].value; }
  int64_t last_modified(size_t i) const { return x_[i].modified; }
  // Value of coordinate i before the current iteration modified it (meaningful when it did).
  double backup(size_t i) const { return x_[i].backup_value; }
  double sigma() const { return sigma_; }

 private:
  struct Coordinate {
    double value = 0.0;
    int64_t modified = -1;  // iteration of the last modification; -1: never set
    double backup_value = 0.0;
    int64_t backup_modified = -1;
  };
  void ensure_ready(size_t i);  // normals by the ziggurat of pss_state.cpp (Marsaglia & Tsang 2000)

  Rng rng_;
  double sigma_;
  std::vector<Coordinate> x_;
  // Coordinates modified in the current iteration (each once): reject() restores these only,
  // instead of scanning every coordinate of the state.
  std::vector<uint32_t> touched_;
  int64_t iteration_ = 0;
  int64_t last_large_ = 0;  // last accepted large step (iteration 0: the initial draw)
  bool large_ = false;      // iteration 0 is the initial draw: no mutation applied
  int stream_ = 0;
  std::array<size_t, kStreams> index_{};
  bool rescaled_ = false;
  double sigma_shared_ = 0.0;                       // sigma(x) of the current rescaled small step
  std::array<size_t, kStreams> current_reads_{};    // D(x): coordinates per stream the current state read
};

// A fixed state u in [0,1)^n, read through the same stream layout (coordinate i * kStreams + s).
// For the checks, whose states are plain vectors. Reading past the end throws std::out_of_range.
class DenseStreams final : public StreamUniforms {
 public:
  explicit DenseStreams(const std::vector<double>& u) : u_(&u) {}
  double next() override;
  void use_stream(int stream) override { stream_ = stream; }
  void restart() override { index_.fill(0); }
  size_t max_read() const { return max_read_; }  // 1 + the largest coordinate read
  const std::array<size_t, kStreams>& reads() const { return index_; }  // per stream, since restart

 private:
  const std::vector<double>* u_;
  int stream_ = 0;
  std::array<size_t, kStreams> index_{};
  size_t max_read_ = 0;
};

}  // namespace tb::pss
