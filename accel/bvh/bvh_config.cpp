#include "accel/bvh/bvh_config.h"

#include <algorithm>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include "accel/bvh/bvh_wide_node.h"
#include "accel/core/simd/simd.h"
#include "accel/core/triangle_test_param.h"
#include "accel/core/simd_param.h"

namespace raylab {

namespace {

// A parameter row: its declaration and the field it fills.
struct BvhParam {
  ParamInfo info;
  void (*assign)(BvhConfig&, const Params&, const ParamInfo&);
};

size_t word_index(const ParamInfo& info, const std::string& word) {
  const auto& w = info.check.words;
  const auto it = std::find(w.begin(), w.end(), word);
  if (it == w.end()) throw std::logic_error("bvh: parameter " + info.name + " has no word " + word);
  return static_cast<size_t>(it - w.begin());
}

// The value of `info` in `p`, as the type of the field: enumerators by the
// index of their word, numbers with a word ("auto") as 0.
template <typename T>
void assign_value(T& field, const Params& p, const ParamInfo& info) {
  const std::string& text = p.str(info.name);
  if constexpr (std::is_enum_v<T>) {
    field = static_cast<T>(word_index(info, text));
  } else if constexpr (std::is_same_v<T, bool>) {
    field = p.boolean(info.name);
  } else {
    const bool word = std::find(info.check.words.begin(), info.check.words.end(), text) != info.check.words.end();
    if constexpr (std::is_integral_v<T>) field = word ? 0 : static_cast<T>(p.integer(info.name));
    else field = word ? T{} : static_cast<T>(p.real(info.name));
  }
}

template <auto kField>
BvhParam row(ParamInfo info) {
  return {std::move(info), [](BvhConfig& c, const Params& p, const ParamInfo& i) { assign_value(c.*kField, p, i); }};
}

std::string preset_help() {
  std::string s = "what the build favours, as values of the parameters below (one given beside it wins; measured "
                  "against the default on the interior views, docs/structures/bvh.md):";
  const char* sep = " ";
  for (const auto& pr : bvh_presets()) {
    s += fmt::format("{}{} = {}{}{}", sep, pr.name, *pr.params ? pr.params : "", *pr.params ? ", " : "", pr.tradeoff);
    sep = "; ";
  }
  return s;
}

const std::vector<BvhParam>& parameter_rows() {
  static const std::vector<BvhParam> rows = [] {
    std::vector<std::string> preset_names;
    for (const auto& pr : bvh_presets()) preset_names.push_back(pr.name);
    return std::vector<BvhParam>{
        row<&BvhConfig::preset>({"preset", "default", preset_help(), one_of(preset_names)}),
        row<&BvhConfig::builder>(
            {"builder", "binned",
             "binary tree builder: binned (SAH over bins; large references in a child of their own), sweep "
             "(full-sweep SAH), sbvh (spatial splits), lbvh (Morton)",
             one_of({"binned", "sweep", "sbvh", "lbvh"})}),
        row<&BvhConfig::opt>(
            {"opt", "light",
             "post-build optimisation: none, light (four reinsertion rounds over the worst 0.5 % of the nodes, "
             "3-triangle binary leaves) or reinsert (up to 32 rounds over 15 %, single-triangle leaves)",
             one_of({"none", "light", "reinsert"})}),
        row<&BvhConfig::layout>(
            {"layout", "auto",
             "traversal layout: bvh2, bvh4, bvh8, bvh16 (16-wide nodes, 448 bytes: one AVX-512 instruction per "
             "plane) or auto (bvh16 where the kernel is AVX-512, else bvh8)",
             one_of({"auto", "bvh2", "bvh4", "bvh8", "bvh16"})}),
        row<&BvhConfig::leaf>({"leaf", "auto",
                               fmt::format("max triangles per leaf (auto: bvh2 4, wide layouts 2 blocks of {})",
                                           kBvhBlockWidth),
                               integer_in(1, 255).or_word("auto")}),
        row<&BvhConfig::bins>({"bins", "64",
                               "SAH bins per axis for nodes of 1024 references or more (fewer below: 8 under 128, "
                               "16 under 1024)",
                               integer_in(2, 256)}),
        row<&BvhConfig::split_budget>({"sbudget", "0.5",
                                       "sbvh: split budget, extra references as a fraction of the triangle count",
                                       real_in(0, 4).as_float()}),
        row<&BvhConfig::spatial_min>({"smin", "0", "sbvh: try spatial splits only at nodes with at least this many references",
                                      integer_in(0, kUnbounded)}),
        row<&BvhConfig::node_cost>({"ct", "2", "collapse SAH cost of a node visit (relative to ci)",
                                    real_in(0, kUnbounded, Ends::Open).as_float()}),
        row<&BvhConfig::block_cost>({"ci", "1", "collapse SAH cost of a triangle block test (bvh2: of a triangle)",
                                     real_in(0, kUnbounded, Ends::Open).as_float()}),
        row<&BvhConfig::tri>({triangle_test_param("; mt: not with simd=0 or packet=16")}),
        row<&BvhConfig::packet>({"packet", "0",
                                 "bvh8, bvh16: 0 (single rays) or 16 (closest-hit batches: 16 rays from one origin as "
                                 "one frustum, other rays singly)",
                                 integer_of({0, 16})}),
        row<&BvhConfig::bound>({"bound", "box",
                                "node bounds: box, or sphere (Ritter spheres on the bvh2 tree; layout=bvh2 implied)",
                                one_of({"box", "sphere"})}),
        row<&BvhConfig::simd>(
            {simd_param("SIMD node and leaf tests", " and counts; bvh2 is scalar either way")}),
    };
  }();
  return rows;
}

std::vector<ParamInfo> declared() {
  std::vector<ParamInfo> out;
  for (const auto& r : parameter_rows()) out.push_back(r.info);
  return out;
}

}  // namespace

int BvhConfig::width() const {
  switch (layout) {
    case BvhLayout::Bvh2: return 2;
    case BvhLayout::Bvh4: return 4;
    case BvhLayout::Bvh16: return 16;
    default: return 8;
  }
}

const std::vector<BvhPresetInfo>& bvh_presets() {
  // The trade-offs: docs/structures/bvh.md, "Presets" (the command and machine there).
  static const std::vector<BvhPresetInfo> presets = {
      {"fast", "opt=none", "no reinsertion pass: build 0.75-0.8x the default's, rays 0.7x (shadow) to 0.96x"},
      {"default", "", "the defaults below"},
      {"quality", "opt=reinsert", "the full reinsertion pass: build 3-19x, rays 1.0-1.04x"},
      {"sbvh", "builder=sbvh,smin=4000,opt=reinsert",
       "spatial splits at nodes of 4000 references or more, the full pass: build 5-15x, camera rays 1.09x, "
       "shadow rays 0.8x"},
  };
  return presets;
}

std::vector<ParamInfo> bvh_parameters() { return declared(); }

BvhConfig bvh_config(const Params& given) {
  // The preset's assignments, then what the spec gives (checked again together).
  const auto& rows = parameter_rows();
  const BvhPresetInfo& preset = bvh_presets()[word_index(rows[0].info, given.str("preset"))];
  std::map<std::string, std::string> values;
  for (const std::string& kv : split_at(preset.params, ',')) {
    if (kv.empty()) continue;
    const auto eq = kv.find('=');
    values[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  for (const auto& r : rows)
    if (given.given(r.info.name)) values[r.info.name] = given.str(r.info.name);
  const Params p("bvh", declared(), values);
  BvhConfig c;
  for (const auto& r : rows) r.assign(c, p, r.info);

  const bool spheres = c.bound == BvhBound::Sphere;
  if (spheres && c.layout != BvhLayout::Auto && c.layout != BvhLayout::Bvh2)
    throw SpecError("bvh: bound=sphere needs layout=bvh2");
  // layout=auto: 16-wide nodes where one AVX-512 instruction tests a plane of
  // all sixteen children; they beat bvh8 on every ray set of the interior
  // views there. Elsewhere a 16-wide plane takes two or four instructions,
  // and bvh8 stays the layout (docs/structures/bvh.md).
  if (spheres) c.layout = BvhLayout::Bvh2;
  else if (c.layout == BvhLayout::Auto) c.layout = simd::isa_bits() >= 512 ? BvhLayout::Bvh16 : BvhLayout::Bvh8;
  const bool wide = c.layout != BvhLayout::Bvh2;
  if (c.leaf == 0) c.leaf = wide ? 2 * kBvhBlockWidth : 4;
  const int max_leaf = wide ? static_cast<int>(wide_ref::kMaxBlocks) * kBvhBlockWidth : 255;
  if (c.leaf > max_leaf) throw SpecError(fmt::format("bvh: leaf must be in 1..{}", max_leaf));

  // opt=light, the default: four rounds over the worst 0.5 % of the nodes of
  // a tree with leaves of up to 3 triangles. A few rounds of small batches
  // move the few badly placed subtrees that cost incoherent rays most, and
  // leaves of 3 instead of 4 let them move alone: +20 % on shadow rays, +6 %
  // random, +3 % diffuse over one round of 2 % on 4-triangle leaves, for a
  // build still near Embree's. The full reinsertion moves single-triangle
  // leaves (+4 % over 4-triangle leaves on all four ray sets).
  const bool full = c.opt == BvhOpt::Reinsert;
  c.binary_leaf = full ? 1 : c.opt == BvhOpt::Light ? 3 : 4;
  c.opt_rounds = full ? 32 : 4;
  c.opt_batch = full ? 0.15 : 0.005;
  // The size split (binned only): at nodes of 1024 references or more, those
  // with boxes above a tenth of the node box's area (or 3 % of the root's)
  // become a child of their own, so floors and walls stop stretching every
  // box on their way down: camera rays -7 % node tests, shadow rays -21 %.
  if (c.builder == BvhBuilder::Binned) c.big_node = 0.1f, c.big_root = 0.03f;
  // Thick leaves (collapse_wide.h), on 16-wide trees after the light pass:
  // camera rays +4 %, shadow +3 %. Off with 8-wide nodes, where an opened
  // leaf costs a level of its own (Sponza's shadow rays 0.6x), and with the
  // full reinsertion, which moves such triangles apart itself.
  c.thick_limit = c.layout == BvhLayout::Bvh16 && !full ? 0.4f : 0.0f;

  if (!c.simd && c.packet != 0) throw SpecError("bvh: packet=16 needs simd=1");
  if (c.packet != 0 && c.layout != BvhLayout::Bvh8 && c.layout != BvhLayout::Bvh16)
    throw SpecError("bvh: packet=16 needs layout=bvh8 or bvh16");
  if (c.tri != TriangleTest::Watertight && wide && (!c.simd || c.packet != 0))
    throw SpecError("bvh: tri=mt with a wide layout needs simd=1 and packet=0 (the scalar and packet tests are watertight only)");
  return c;
}

}  // namespace raylab
