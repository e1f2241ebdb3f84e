#include "lib/mcmc/path_space/ramlt.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <nlohmann/json.hpp>

#include "estimators/mcmc/chain_step.h"
#include "estimators/mcmc/metropolis_hastings.h"
#include "lib/core/atomic_file.h"
#include "lib/core/hash.h"
#include "lib/core/parallel.h"
#include "lib/film/png_preview.h"
#include "lib/mcmc/path_space/bidirectional_mutation.h"
#include "lib/mcmc/path_space/mlt_chain.h"
#include "lib/mcmc/path_space/ramlt_adaptation.h"
#include "lib/mcmc/path_space/ramlt_perturbations.h"
#include "lib/mcmc/path_space/start_paths.h"

namespace tb::path_space {

namespace {

struct Observation {
  int region;   // screen region (sigma_1)
  int region2;  // 4d region (sigma_2), -1 without a 4d partition
  double acceptance;
};

bool is_4d(const std::string& p) { return p == "grid4d" || p == "quadtree4d"; }

}  // namespace

RamltStats run_ramlt(const World& world, const RenderSettings& st, Film& film, const RamltOptions& opt) {
  const Camera& cam = world.camera();
  if (!cam.lens_is_delta()) throw std::invalid_argument("ramlt: path-space MLT needs a pinhole camera");
  if (st.time_budget_s > 0)
    throw std::invalid_argument("ramlt: the chains share their adaptation; time budgets are not supported");
  const LightSampler sampler(world);
  const PathContext ctx{&world, &sampler};
  const int max_depth = std::max(0, st.max_depth);
  const PathTarget target{&ctx};

  // Partition and the shared scales (Otsu Sec. 5.2-5.4).
  // The quadtree is refined between batches: the driver keeps the non-const tree.
  std::shared_ptr<mcmc::QuadtreePartition> tree;
  std::shared_ptr<const ScreenPartition> partition;
  // 4d (Otsu Sec. 5.4, 6.3): sigma_1 on the N_top grid, sigma_2 on the 4d regions.
  const bool four_d = is_4d(opt.partition);
  if (four_d && opt.perturbation != RamltPerturbation::kMultiChain)
    throw std::invalid_argument("ramlt: the 4d partitions (" + opt.partition + ") are the multi-chain perturbation's");
  std::shared_ptr<mcmc::GridQuadtreePartition> tree4;
  std::shared_ptr<const Screen4dPartition> partition2;
  if (opt.partition == "quadtree4d") {
    tree4 = std::make_shared<mcmc::GridQuadtreePartition>(std::array<double, 4>{0.0, 0.0, 0.0, 0.0},
                                                          std::array<double, 4>{1.0, 1.0, 1.0, 1.0}, opt.grid,
                                                          opt.quadtree_max_depth);
    partition2 = std::make_shared<const Screen4dPartition>(ctx, tree4);
  } else if (four_d) {
    partition2 = Screen4dPartition::make(ctx, opt.partition, opt.grid, opt.grid_bottom);
  }
  if (four_d) {
    partition = ScreenPartition::make(ctx, "grid", opt.grid);
  } else if (opt.partition == "quadtree") {
    tree = std::make_shared<mcmc::QuadtreePartition>(std::array<double, 2>{0.0, 0.0}, std::array<double, 2>{1.0, 1.0},
                                                     opt.quadtree_max_depth);
    partition = std::make_shared<const ScreenPartition>(ctx, tree);
  } else {
    partition = ScreenPartition::make(ctx, opt.partition, opt.grid);
  }
  int R = partition->regions();
  SplittableAdaptation<> adapter(R, opt.adaptation, opt.keep_record, !partition->adapts());
  auto lambda = std::make_shared<std::vector<double>>(static_cast<size_t>(R), opt.adaptation.lambda0);
  int R2 = partition2 ? partition2->regions() : 0;
  SplittableAdaptation<> adapter2(R2, opt.adaptation);
  auto lambda2 = std::make_shared<std::vector<double>>(static_cast<size_t>(R2), opt.adaptation.lambda0);
  RegionalScale scale{partition, lambda};
  if (partition2) {
    scale.partition2 = partition2;
    scale.lambda2 = lambda2;
  }

  std::shared_ptr<const PathMutation> pert;
  if (opt.perturbation == RamltPerturbation::kLens)
    pert = std::make_shared<const RamltLensMutation>("ramlt-lens", opt.perturbation_weight, RamltLensPerturbation(ctx, scale));
  else
    pert = std::make_shared<const RamltMultiChainMutation>("ramlt-multichain", opt.perturbation_weight,
                                                           RamltMultiChainPerturbation(ctx, scale));
  PathMutationList parts{std::make_shared<const PathProposalMutation<BidirectionalMutation>>(
                             "bidirectional", opt.bidirectional_weight, BidirectionalMutation(ctx, max_depth + 1)),
                         pert};
  if (opt.wrap) parts = opt.wrap(std::move(parts));
  const PathMixture mixture(std::move(parts));
  constexpr int kAdaptive = 1;
  const size_t K = static_cast<size_t>(mixture.components());

  const int64_t P = cam.pixel_count();
  const int64_t C = std::max<int64_t>(1, st.passes);
  const int64_t M = std::max<int64_t>(1, st.spp * P / C);
  const int64_t n_boot = opt.bootstrap_per_chain > 0 ? opt.bootstrap_per_chain : std::max<int64_t>(256, 4 * P / C);
  const auto batch_length = [&](int regions) {
    return std::clamp<int64_t>(
        opt.batch_steps > 0 ? opt.batch_steps : (static_cast<int64_t>(opt.adaptation.batch) * regions + C - 1) / C, 1, M);
  };
  int64_t B = batch_length(R);

  RamltStats out;
  out.batch_steps = B;
  MltStats& stats = out.mlt;
  for (int k = 0; k < mixture.components(); ++k) stats.mutations.push_back(MutationStats{mixture.name(k)});
  RamltRegionMaps& maps = out.maps;
  maps.partition = four_d ? opt.partition : partition->name();
  maps.regions = R;
  std::vector<int64_t> since_refine(static_cast<size_t>(R), 0);  // reports per leaf since the last refinement
  std::vector<int64_t> since_refine2(static_cast<size_t>(R2), 0);
  maps.visits2.assign(static_cast<size_t>(R2), 0);
  maps.acceptance_sum2.assign(static_cast<size_t>(R2), 0.0);
  int64_t mutations_since_refine = 0;
  const auto t0 = std::chrono::steady_clock::now();

  // Start-up of every chain (mlt.h): bootstrap b_c and the resampled start path.
  const size_t n = static_cast<size_t>(C);
  std::vector<Rng> rng;
  rng.reserve(n);
  for (size_t c = 0; c < n; ++c) rng.push_back(Rng::for_sample(st.seed, hash_string("ramlt.chain"), c));
  std::vector<double> b(n, 0.0);
  std::vector<MltChain> chain(n);
  std::vector<char> alive(n, 0);
  std::vector<SplatBuffer> splats(n, SplatBuffer(film.width(), film.height()));
  std::vector<std::vector<mcmc::ComponentCounts>> local(n, std::vector<mcmc::ComponentCounts>(K));
  parallel_for(n, [&](size_t c) {
    RngUniforms u(rng[c]);
    ChainStart s = start_chain(ctx, st.seed, c, n_boot, max_depth, u.next());
    b[c] = s.b;
    if (!s.x) return;
    MltChain& ch = chain[c];
    ch.mix = &mixture;
    ch.target = &target;
    ch.x = std::move(*s.x);
    ch.fx = target.contribution(ch.x);
    ch.pix = std::max(0.0, luminance(ch.fx));
    ch.start();
    alive[c] = 1;
  });

  // Synchronous batches: B steps per chain at frozen lambda, then the reports in chain order.
  std::vector<std::vector<Observation>> obs(n);
  double adapt_s = 0.0;
  int64_t done = 0;  // steps run by every live chain
  while (done < M) {
    if (st.interrupted && st.interrupted->load()) break;
    const int64_t steps = std::min(B, M - done);
    parallel_for(n, [&](size_t c) {
      obs[c].clear();
      if (!alive[c]) return;
      MltChain& ch = chain[c];
      RngUniforms u(rng[c]);
      auto& ls = local[c];
      int rx = -1, rx2 = -1;  // regions of the current path, recomputed after an accepted move
      for (int64_t s = 0; s < steps; ++s) {
        if (rx < 0) {
          rx = partition->region_of(ch.x);
          rx2 = scale.region2(ch.x);
        }
        const uint64_t index = static_cast<uint64_t>(done + s);
        const mcmc::StepOutcome o = mcmc::chain_step(ch, u, u, [&](mcmc::Which which, double w) {
          const bool cur = which == mcmc::Which::kCurrent;
          const double pi = cur ? ch.pix : ch.piy;
          if (!(pi > 0.0)) return;
          const auto r = path_raster(ctx, cur ? ch.x : *ch.y);
          if (r) splats[c].splat(*r, (cur ? ch.fx : ch.fy) * (w / pi), index);
        });
        if (o.component >= 0) ls[static_cast<size_t>(o.component)].add(o);
        if (o.component == kAdaptive) obs[c].push_back({rx, rx2, o.acceptance});  // Algorithm 1, line 11
        if (o.accepted) rx = -1;
      }
    });
    const auto ta = std::chrono::steady_clock::now();
    for (size_t c = 0; c < n; ++c)
      for (const Observation& ob : obs[c]) {
        ++since_refine[static_cast<size_t>(ob.region)];
        if (maps.visits.size() < static_cast<size_t>(R)) {
          maps.visits.resize(static_cast<size_t>(R), 0);
          maps.acceptance_sum.resize(static_cast<size_t>(R), 0.0);
        }
        maps.acceptance_sum[static_cast<size_t>(ob.region)] += ob.acceptance;
        ++maps.visits[static_cast<size_t>(ob.region)];
        adapter.observe(ob.region, ob.acceptance);  // lines 11-18, Eq. 4-6 (frozen: FIXED)
        if (ob.region2 >= 0) {
          const size_t r2 = static_cast<size_t>(ob.region2);
          ++since_refine2[r2];
          ++maps.visits2[r2];
          maps.acceptance_sum2[r2] += ob.acceptance;
          adapter2.observe(ob.region2, ob.acceptance);
        }
      }
    // Quadtree refinement (Otsu Sec. 6.2): each leaf existing now with more than M_split reports
    // is split once; its children inherit lambda and n_k / 4 (SplittableAdaptation::split).
    mutations_since_refine += steps * C;
    if (tree && mutations_since_refine >= opt.refine_every) {
      mutations_since_refine = 0;
      const int leaves = R;
      bool split_any = false;
      for (int r = 0; r < leaves; ++r) {
        if (since_refine[static_cast<size_t>(r)] <= opt.split_threshold || !tree->can_split(r)) continue;
        tree->split(r);
        adapter.split(r, 3);
        if (static_cast<size_t>(r) < maps.visits.size()) {  // the maps count reports since the leaf was made
          maps.visits[static_cast<size_t>(r)] = 0;
          maps.acceptance_sum[static_cast<size_t>(r)] = 0.0;
        }
        split_any = true;
      }
      R = tree->regions();
      since_refine.assign(static_cast<size_t>(R), 0);
      if (split_any) {
        ++maps.refinements;
        B = batch_length(R);
      }
    }
    // The same refinement on each screen cell's direction quadtree (Otsu Sec. 6.3).
    if (tree4 && mutations_since_refine >= opt.refine_every) {
      mutations_since_refine = 0;
      const int leaves = R2;
      bool split_any = false;
      for (int r = 0; r < leaves; ++r) {
        if (since_refine2[static_cast<size_t>(r)] <= opt.split_threshold || !tree4->can_split(r)) continue;
        tree4->split(r);
        adapter2.split(r, 3);
        maps.visits2[static_cast<size_t>(r)] = 0;
        maps.acceptance_sum2[static_cast<size_t>(r)] = 0.0;
        split_any = true;
      }
      R2 = tree4->regions();
      since_refine2.assign(static_cast<size_t>(R2), 0);
      maps.visits2.resize(static_cast<size_t>(R2), 0);
      maps.acceptance_sum2.resize(static_cast<size_t>(R2), 0.0);
      if (split_any) ++maps.refinements;
    }
    lambda->resize(static_cast<size_t>(R));
    for (int r = 0; r < R; ++r) (*lambda)[static_cast<size_t>(r)] = adapter.lambda(r);
    lambda2->resize(static_cast<size_t>(R2));
    for (int r = 0; r < R2; ++r) (*lambda2)[static_cast<size_t>(r)] = adapter2.lambda(r);
    adapt_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - ta).count();
    ++out.batches;
    done += steps;
    if (st.progress) st.progress(static_cast<double>(done) / static_cast<double>(M));
  }
  out.adaptation_seconds = adapt_s;
  out.batch_steps = B;  // the last batch length (a quadtree lengthens it as it grows)

  // A pass range gets the chains of the range from the whole coupled run (pass_loop.h's contract:
  // a range's film does not depend on how the run is cut).
  const int64_t first = std::clamp<int64_t>(st.first_pass, 0, C);
  const int64_t end = st.pass_count < 0 ? C : std::min(C, first + st.pass_count);
  double b_sum = 0.0;
  for (size_t c = static_cast<size_t>(first); c < static_cast<size_t>(std::max(first, end)); ++c) {
    film.merge_splats(splats[c]);
    // Splat scale P b_c / (steps run): M, or fewer when interrupted.
    const double sc = done > 0 ? static_cast<double>(P) * b[c] / static_cast<double>(done) : 0.0;
    film.end_pass(splats[c].entries().empty() ? 0.0 : sc);
    b_sum += b[c];
    if (!alive[c]) ++stats.chains_without_start;
    stats.mutations_total += alive[c] ? done : 0;
    for (size_t k = 0; k < K; ++k) {
      stats.mutations[k].add(local[c][k]);
    }
    ++stats.chains;
  }
  stats.b_mean = stats.chains > 0 ? b_sum / static_cast<double>(stats.chains) : 0.0;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  maps.regions = R;
  maps.visits.resize(static_cast<size_t>(R), 0);
  maps.acceptance_sum.resize(static_cast<size_t>(R), 0.0);
  maps.lambda.resize(static_cast<size_t>(R));
  maps.updates.resize(static_cast<size_t>(R));
  for (int r = 0; r < R; ++r) {
    maps.lambda[static_cast<size_t>(r)] = adapter.lambda(r);
    maps.updates[static_cast<size_t>(r)] = adapter.updates(r);
  }
  maps.width = film.width();
  maps.height = film.height();
  maps.regions2 = R2;
  maps.lambda2.resize(static_cast<size_t>(R2));
  maps.updates2.resize(static_cast<size_t>(R2));
  maps.cell2.resize(static_cast<size_t>(R2));
  for (int r = 0; r < R2; ++r) {
    maps.lambda2[static_cast<size_t>(r)] = adapter2.lambda(r);
    maps.updates2[static_cast<size_t>(r)] = adapter2.updates(r);
    // grid4d: dimension 0 fastest, so the screen cell is the index modulo N_top^2.
    maps.cell2[static_cast<size_t>(r)] = tree4 ? tree4->cell_of(r) : r % (opt.grid * opt.grid);
  }
  out.record = adapter.record();
  std::shared_ptr<const ScreenCellPartition> cells = tree;
  if (!cells)
    cells = mcmc::make_partition<2>(four_d ? "grid" : opt.partition, {{0.0, 0.0}, {1.0, 1.0}, {opt.grid, opt.grid}});
  maps.pixel_region.resize(static_cast<size_t>(maps.width) * static_cast<size_t>(maps.height));
  for (int py = 0; py < maps.height; ++py)
    for (int px = 0; px < maps.width; ++px)
      maps.pixel_region[static_cast<size_t>(py) * static_cast<size_t>(maps.width) + static_cast<size_t>(px)] =
          cells->region_of({(px + 0.5) / maps.width, (py + 0.5) / maps.height});
  if (tree)
    for (int r = 0; r < R; ++r) {
      const auto lo = tree->lo(r), hi = tree->hi(r);
      maps.leaf_boxes.push_back({lo[0], lo[1], hi[0], hi[1]});
    }
  return out;
}

RamltOptions apply_ramlt_params(RamltOptions o, const std::map<std::string, double>& params) {
  const auto get = [&](const char* name, auto& field) {
    const auto it = params.find(name);
    if (it != params.end()) field = static_cast<std::remove_reference_t<decltype(field)>>(it->second);
  };
  get("grid", o.grid);
  get("grid_bottom", o.grid_bottom);
  get("refine_every", o.refine_every);
  get("split_threshold", o.split_threshold);
  get("lambda0", o.adaptation.lambda0);
  get("target_acceptance", o.adaptation.target_acceptance);
  get("batch_steps", o.batch_steps);
  if (o.grid < 1 || o.grid_bottom < 1 || o.refine_every < 1 || o.split_threshold < 0 || o.batch_steps < 0 ||
      !(o.adaptation.target_acceptance > 0.0 && o.adaptation.target_acceptance < 1.0))
    throw std::invalid_argument("ramlt: grid, refine_every >= 1, split_threshold, batch_steps >= 0, 0 < a* < 1");
  return o;
}

std::vector<std::pair<std::string, std::string>> ramlt_parameter_list() {
  return {{"grid", "N_top: N x N screen cells of the grid partition (default 20, Otsu Sec. 8.1)"},
          {"grid_bottom", "N_bottom: direction cells per side of the grid4d partition (default 50, Otsu Sec. 8.1)"},
          {"refine_every", "quadtree: mutations of all chains between refinements (default 1e7)"},
          {"split_threshold", "quadtree: reports of a leaf above which it is split (default 5000)"},
          {"lambda0", "initial lambda = log sigma^2 (default 1)"},
          {"target_acceptance", "a* of Eq. 5 (default 0.5)"},
          {"batch_steps", "steps per chain per synchronous batch (default 0: ceil(L regions / chains))"}};
}

void write_ramlt_maps(const RamltRegionMaps& m, const std::string& base) {
  nlohmann::json j = {{"partition", m.partition}, {"regions", m.regions}, {"lambda", m.lambda},
                      {"visits", m.visits},       {"updates", m.updates}, {"width", m.width},
                      {"height", m.height}};
  std::vector<double> acc(static_cast<size_t>(m.regions));
  for (int r = 0; r < m.regions; ++r) acc[static_cast<size_t>(r)] = m.acceptance(r);
  j["acceptance"] = acc;
  if (m.regions2 > 0) {
    std::vector<double> acc2(static_cast<size_t>(m.regions2));
    for (int r = 0; r < m.regions2; ++r)
      acc2[static_cast<size_t>(r)] = m.visits2[static_cast<size_t>(r)] > 0
                                         ? m.acceptance_sum2[static_cast<size_t>(r)] /
                                               static_cast<double>(m.visits2[static_cast<size_t>(r)])
                                         : 0.0;
    j["sigma2_regions"] = {{"regions", m.regions2}, {"lambda", m.lambda2},   {"visits", m.visits2},
                           {"updates", m.updates2}, {"acceptance", acc2}, {"screen_cell", m.cell2}};
    j["refinements"] = m.refinements;
  }
  if (!m.leaf_boxes.empty()) {
    j["leaf_boxes"] = m.leaf_boxes;
    j["refinements"] = m.refinements;
  }
  write_file_atomic(base + ".ramlt.json", j.dump(1));
  if (m.regions == 0 || m.pixel_region.empty()) return;
  const auto [lmin, lmax] = std::minmax_element(m.lambda.begin(), m.lambda.end());
  const int64_t vmax = *std::max_element(m.visits.begin(), m.visits.end());
  const auto image = [&](auto value) {
    std::vector<Rgb> img(m.pixel_region.size());
    for (size_t i = 0; i < img.size(); ++i) img[i] = Rgb(std::clamp(value(m.pixel_region[i]), 0.0, 1.0));
    return img;
  };
  const double lspan = *lmax - *lmin;
  write_png_preview(base + ".ramlt_lambda.png", m.width, m.height,
                    image([&](int r) { return lspan > 0 ? (m.lambda[static_cast<size_t>(r)] - *lmin) / lspan : 0.5; }));
  write_png_preview(base + ".ramlt_acceptance.png", m.width, m.height, image([&](int r) { return m.acceptance(r); }));
  write_png_preview(base + ".ramlt_visits.png", m.width, m.height, image([&](int r) {
                      return vmax > 0 ? static_cast<double>(m.visits[static_cast<size_t>(r)]) / static_cast<double>(vmax) : 0.0;
                    }));
}

}  // namespace tb::path_space

namespace tb {

int64_t render_ramlt(const World& world, const RenderSettings& settings, Film& film,
                     const path_space::RamltOptions& options) {
  const path_space::RamltStats stats = path_space::run_ramlt(world, settings, film, options);
  path_space::fill_report(stats.mlt, settings.report);
  return stats.mlt.chains;
}

}  // namespace tb
