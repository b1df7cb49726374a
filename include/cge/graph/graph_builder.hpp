#pragma once
// GraphBuilder: the frame graph of docs/METHOD.md section 3, built for one frame with respect to a
// partner frame (stability depends on both frames' dynamic masks).
//
// Determinism: the output depends only on the input values, never on their order (nodes are put
// in canonical order first) nor on the neighbour-search policy. build() is const and re-entrant: it
// works on a copy of the configured policy and keeps no state between calls. The allocation-free
// form build(..., out, workspace) is re-entrant too as long as each thread has its own workspace
// and output graph.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "cge/core/concepts.hpp"
#include "cge/core/image_region.hpp"
#include "cge/core/mask.hpp"
#include "cge/core/nearest_pixel.hpp"
#include "cge/core/point_traits.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/neighbor_search.hpp"

namespace cge {

template <typename Scalar>
struct GraphBuilderSettings {
  /// Patch grid over the image (paper: 10 x 10).
  int patch_cols = 10;
  int patch_rows = 10;
  /// N_th: a patch with MORE than this many stable features is dense and is replaced by one
  /// representation point at its centre. Our default (the paper gives no value): about 1.5 times
  /// the mean per patch for 1000 features on 10 x 10 patches.
  int dense_patch_threshold = 15;
  /// R, the base connection radius, as a fraction of the image diagonal (5% = 40 px at 640 x 480).
  Scalar radius_fraction_of_diagonal = Scalar(0.05);
  /// From this round on a centre's radius grows at most to capped_radius_multiple * R.
  int first_capped_round = 3;
  Scalar capped_radius_multiple = Scalar(3);
  /// Safety stop for pathological input; the construction needs at most |V| rounds.
  int max_rounds = std::numeric_limits<int>::max();
};

/// Nodes before edges: what build_nodes() returns and build_edges() consumes.
template <typename Scalar>
struct FrameNodes {
  std::vector<Eigen::Matrix<Scalar, 2, 1>> positions;  ///< canonical order: by (y, x, kind)
  std::vector<NodeKind> kinds;
};

namespace detail {

/// Edges in creation order plus the per-node state of the construction.
struct EdgeConstruction {
  struct NewEdge {
    std::int32_t u, v;  // u < v
    std::uint8_t round;
  };
  // The first edge_count entries are valid. A plain array, not a vector: slots are written
  // before they count (branch-free appends), and zero-filling ~100 kB per build is measurable.
  std::unique_ptr<NewEdge[]> edges;
  std::size_t capacity = 0;
  std::size_t edge_count = 0;
  std::vector<std::uint8_t> connected;  // the paper's flag: 1 once a node is in the graph

  void reset(std::int32_t n) {
    edge_count = 0;
    connected.assign(static_cast<std::size_t>(n), 0);
    reserve_more(static_cast<std::size_t>(n) * 8);
  }
  /// Room for `more` edges past edge_count, so that appends need no capacity check.
  void reserve_more(std::size_t more) {
    if (capacity >= edge_count + more) return;
    const std::size_t grown = std::max(capacity * 2, edge_count + more);
    std::unique_ptr<NewEdge[]> bigger(new NewEdge[grown]);
    std::copy(edges.get(), edges.get() + edge_count, bigger.get());
    edges.swap(bigger);
    capacity = grown;
  }
  void append(std::int32_t a, std::int32_t b, std::uint8_t round) {
    reserve_more(1);
    edges[edge_count++] = NewEdge{a, b, round};
  }
};

/// A node as the canonical sort sees it.
template <typename Scalar>
struct NodeRecord {
  Scalar y, x;
  NodeKind kind;
};

/// True for ranges with a size() member (std::vector, std::array, ...).
template <typename T, typename = void>
struct HasSize : std::false_type {};
template <typename T>
struct HasSize<T, decltype(void(std::declval<const T&>().size()))> : std::true_type {};

/// Grows v to at least n elements without ever shrinking it, so a reused buffer is zero-filled
/// only the first time it reaches a size.
template <typename T>
T* at_least(std::vector<T>& v, std::size_t n) {
  if (v.size() < n) v.resize(n);
  return v.data();
}

}  // namespace detail

/// Buffers that GraphBuilder reuses between builds. Hand the same workspace (and the same output
/// Graph) to every build in a hot loop and nothing is allocated once they have grown to the
/// largest frame seen. A workspace never changes a result. Use one per thread; its contents are
/// scratch, not an interface.
template <typename Scalar, typename NeighborSearch = GridNeighborSearch<Scalar>>
struct GraphBuilderWorkspace {
  using Point = Eigen::Matrix<Scalar, 2, 1>;
  // Node selection.
  std::vector<Point> stable;
  std::vector<std::int32_t> patch_of;
  std::vector<std::int32_t> stable_per_patch;
  FrameNodes<Scalar> nodes;
  std::vector<detail::NodeRecord<Scalar>> records;
  std::vector<std::uint32_t> band_end;
  // Edge construction.
  NeighborSearch search;
  std::vector<Scalar> last_rr;
  std::vector<std::int32_t> centres;
  std::vector<std::uint8_t> next_centre;
  detail::EdgeConstruction construction;
  // Canonical CSR.
  std::vector<std::int32_t> fill;
  std::vector<std::int32_t> start_u;
  std::unique_ptr<detail::EdgeConstruction::NewEdge[]> by_v;
  std::size_t by_v_capacity = 0;
};

template <typename Scalar = double, typename NeighborSearch = GridNeighborSearch<Scalar>>
class GraphBuilder {
 public:
#if CGE_HAS_CONCEPTS
  static_assert(NeighborSearchPolicy<NeighborSearch, Scalar>,
                "NeighborSearch must satisfy the contract in cge/graph/neighbor_search.hpp");
#endif
  using Point = Eigen::Matrix<Scalar, 2, 1>;
  using Settings = GraphBuilderSettings<Scalar>;
  using Workspace = GraphBuilderWorkspace<Scalar, NeighborSearch>;

  Settings settings;
  /// Configured prototype of the neighbour-search policy; copied by every build().
  NeighborSearch neighbor_search;

  GraphBuilder() = default;
  explicit GraphBuilder(const Settings& s, NeighborSearch ns = NeighborSearch())
      : settings(s), neighbor_search(std::move(ns)) {}

  /// Full construction. `keypoints` is any range of point types adapted by cge::traits::Point2;
  /// the masks are any types adapted by cge::traits::Mask (an empty mask means no dynamic objects);
  /// `instances` are this frame's semantic instances, of which the static ones become nodes.
  /// A keypoint is stable when its pixel (coordinates rounded to the nearest integer, relative to
  /// the region's origin) is set in neither mask.
  /// Throws std::invalid_argument for keypoints or instance centres outside the region or not
  /// finite, masks of the wrong size, or bad settings.
  template <typename Keypoints, typename OwnMask, typename PartnerMask>
  Graph<Scalar> build(const ImageRegion<Scalar>& image, const Keypoints& keypoints, const OwnMask& own_dynamic_mask,
                      const PartnerMask& partner_dynamic_mask,
                      const std::vector<SemanticInstance<Scalar>>& instances) const {
    Workspace workspace;
    Graph<Scalar> graph;
    build(image, keypoints, own_dynamic_mask, partner_dynamic_mask, instances, graph, workspace);
    return graph;
  }

  /// The same construction into `out`, reusing its storage and the workspace's buffers: the
  /// allocation-free form for hot loops. The result equals build()'s, bit for bit.
  template <typename Keypoints, typename OwnMask, typename PartnerMask>
  void build(const ImageRegion<Scalar>& image, const Keypoints& keypoints, const OwnMask& own_dynamic_mask,
             const PartnerMask& partner_dynamic_mask, const std::vector<SemanticInstance<Scalar>>& instances,
             Graph<Scalar>& out, Workspace& workspace) const {
    select_nodes(image, keypoints, own_dynamic_mask, partner_dynamic_mask, instances, workspace);
    connect_nodes(image, out, workspace);
  }

  /// Same as build() with no masks: every keypoint counts as stable.
  template <typename Keypoints>
  Graph<Scalar> build(const ImageRegion<Scalar>& image, const Keypoints& keypoints,
                      const std::vector<SemanticInstance<Scalar>>& instances = {}) const {
    return build(image, keypoints, NoMask{}, NoMask{}, instances);
  }

  /// Node selection only: stable features, dense patches, semantic nodes, canonical order, exact
  /// duplicates merged (the first in canonical order, so the lowest NodeKind, is kept).
  template <typename Keypoints, typename OwnMask, typename PartnerMask>
  FrameNodes<Scalar> build_nodes(const ImageRegion<Scalar>& image, const Keypoints& keypoints,
                                 const OwnMask& own_dynamic_mask, const PartnerMask& partner_dynamic_mask,
                                 const std::vector<SemanticInstance<Scalar>>& instances) const {
    Workspace workspace;
    select_nodes(image, keypoints, own_dynamic_mask, partner_dynamic_mask, instances, workspace);
    return std::move(workspace.nodes);
  }

  /// Edge construction over nodes already in canonical order (as build_nodes returns them).
  Graph<Scalar> build_edges(const ImageRegion<Scalar>& image, FrameNodes<Scalar> nodes) const {
    validate(image);  // the other entry points validate in select_nodes
    if (nodes.kinds.size() != nodes.positions.size()) {
      throw std::invalid_argument("GraphBuilder: FrameNodes has different numbers of positions and kinds");
    }
    Workspace workspace;
    workspace.nodes = std::move(nodes);
    Graph<Scalar> graph;
    connect_nodes(image, graph, workspace);
    return graph;
  }

  /// R in pixels for an image region.
  Scalar base_radius(const ImageRegion<Scalar>& image) const {
    return settings.radius_fraction_of_diagonal * image.diagonal();
  }

 private:
  /// Node selection into workspace.nodes: stable features, dense patches, semantic nodes,
  /// canonical order, exact duplicates merged.
  template <typename Keypoints, typename OwnMask, typename PartnerMask>
  void select_nodes(const ImageRegion<Scalar>& image, const Keypoints& keypoints, const OwnMask& own_dynamic_mask,
                    const PartnerMask& partner_dynamic_mask, const std::vector<SemanticInstance<Scalar>>& instances,
                    Workspace& ws) const {
#if CGE_HAS_CONCEPTS
    static_assert(Point2Like<std::decay_t<decltype(*std::begin(keypoints))>>,
                  "keypoints must be a range of points adapted by cge::traits::Point2 (cge/core/point_traits.hpp)");
    static_assert(MaskLike<OwnMask> && MaskLike<PartnerMask>,
                  "masks must be adapted by cge::traits::Mask (cge/core/mask.hpp)");
#endif
    validate(image);
    const int mask_w = static_cast<int>(std::lround(image.width_px));
    const int mask_h = static_cast<int>(std::lround(image.height_px));
    check_mask_size(own_dynamic_mask, mask_w, mask_h, "own dynamic mask");
    check_mask_size(partner_dynamic_mask, mask_w, mask_h, "partner dynamic mask");
    const bool own_empty = traits::Mask<OwnMask>::empty(own_dynamic_mask);
    const bool partner_empty = traits::Mask<PartnerMask>::empty(partner_dynamic_mask);

    const int patch_count = settings.patch_cols * settings.patch_rows;
    std::vector<std::int32_t>& patch_of = ws.patch_of;  // per stable feature
    std::vector<Point>& stable = ws.stable;
    std::vector<std::int32_t>& stable_per_patch = ws.stable_per_patch;
    patch_of.clear();
    stable.clear();
    // Reserve once where the count is cheap to know: growing by doubling copies, and touches
    // twice the memory, which a fresh build pays for in page faults.
    if constexpr (detail::HasSize<Keypoints>::value) {
      stable.reserve(keypoints.size());
      patch_of.reserve(keypoints.size());
    }
    stable_per_patch.assign(static_cast<std::size_t>(patch_count), 0);
    const Scalar patch_w = image.width_px / static_cast<Scalar>(settings.patch_cols);
    const Scalar patch_h = image.height_px / static_cast<Scalar>(settings.patch_rows);

    std::size_t index = 0;
    for (const auto& kp : keypoints) {
      const Point p(static_cast<Scalar>(point_x(kp)), static_cast<Scalar>(point_y(kp)));
      if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !image.contains(p)) {
        std::ostringstream msg;
        msg << "GraphBuilder: keypoint #" << index << " at (" << p.x() << ", " << p.y()
            << ") is not finite or lies outside the image region";
        throw std::invalid_argument(msg.str());
      }
      ++index;
      const Point rel = p - image.origin_px;
      if (!own_empty || !partner_empty) {
        const int col = nearest_pixel_index(static_cast<double>(rel.x()), mask_w);
        const int row = nearest_pixel_index(static_cast<double>(rel.y()), mask_h);
        if (!own_empty && traits::Mask<OwnMask>::is_set(own_dynamic_mask, col, row)) continue;
        if (!partner_empty && traits::Mask<PartnerMask>::is_set(partner_dynamic_mask, col, row)) continue;
      }
      const int pc = std::min(static_cast<int>(rel.x() / patch_w), settings.patch_cols - 1);
      const int pr = std::min(static_cast<int>(rel.y() / patch_h), settings.patch_rows - 1);
      const std::int32_t patch = pr * settings.patch_cols + pc;
      stable.push_back(p);
      patch_of.push_back(patch);
      ++stable_per_patch[static_cast<std::size_t>(patch)];
    }

    FrameNodes<Scalar>& nodes = ws.nodes;
    nodes.positions.clear();
    nodes.kinds.clear();
    nodes.positions.reserve(stable.size() + static_cast<std::size_t>(patch_count) + instances.size());
    nodes.kinds.reserve(nodes.positions.capacity());
    for (int patch = 0; patch < patch_count; ++patch) {
      if (stable_per_patch[static_cast<std::size_t>(patch)] > settings.dense_patch_threshold) {
        const int pc = patch % settings.patch_cols;
        const int pr = patch / settings.patch_cols;
        nodes.positions.emplace_back(image.origin_px.x() + (static_cast<Scalar>(pc) + Scalar(0.5)) * patch_w,
                                     image.origin_px.y() + (static_cast<Scalar>(pr) + Scalar(0.5)) * patch_h);
        nodes.kinds.push_back(NodeKind::representation);
      }
    }
    for (std::size_t i = 0; i < stable.size(); ++i) {
      if (stable_per_patch[static_cast<std::size_t>(patch_of[i])] <= settings.dense_patch_threshold) {
        nodes.positions.push_back(stable[i]);
        nodes.kinds.push_back(NodeKind::feature);
      }
    }
    for (std::size_t i = 0; i < instances.size(); ++i) {
      const SemanticInstance<Scalar>& inst = instances[i];
      if (!std::isfinite(inst.centre_px.x()) || !std::isfinite(inst.centre_px.y()) || !image.contains(inst.centre_px)) {
        std::ostringstream msg;
        msg << "GraphBuilder: semantic instance #" << i << " has centre (" << inst.centre_px.x() << ", "
            << inst.centre_px.y() << ") that is not finite or lies outside the image region";
        throw std::invalid_argument(msg.str());
      }
      if (inst.dynamic) continue;
      nodes.positions.push_back(inst.centre_px);
      nodes.kinds.push_back(NodeKind::semantic);
    }
    canonicalise(image, ws);
  }

  /// Edges over workspace.nodes (canonical order, validated by the caller) into out.
  void connect_nodes(const ImageRegion<Scalar>& image, Graph<Scalar>& out, Workspace& ws) const {
    const std::int32_t n = static_cast<std::int32_t>(ws.nodes.positions.size());
    ws.construction.reset(n);
    if (n >= 2) {
      connect(image, ws.nodes.positions, ws);
      join_strays(ws.nodes.positions, ws.construction);
    }
    to_graph(ws, out);
  }

  void validate(const ImageRegion<Scalar>& image) const {
    image.validate();
    if (settings.patch_cols < 1 || settings.patch_rows < 1) {
      throw std::invalid_argument("GraphBuilderSettings: patch_cols and patch_rows must be at least 1");
    }
    if (settings.dense_patch_threshold < 0) {
      throw std::invalid_argument("GraphBuilderSettings: dense_patch_threshold must not be negative");
    }
    if (!(settings.radius_fraction_of_diagonal > 0) || !std::isfinite(settings.radius_fraction_of_diagonal)) {
      throw std::invalid_argument("GraphBuilderSettings: radius_fraction_of_diagonal must be finite and positive");
    }
    if (!(settings.capped_radius_multiple >= 1) || !std::isfinite(settings.capped_radius_multiple)) {
      throw std::invalid_argument("GraphBuilderSettings: capped_radius_multiple must be finite and at least 1");
    }
    if (settings.first_capped_round < 1) {
      throw std::invalid_argument("GraphBuilderSettings: first_capped_round must be at least 1");
    }
  }

  /// Sorts by (y, x, kind) and merges exact duplicates. A counting sort into horizontal bands
  /// (monotone in y) does most of the work without data-dependent branches; each band's few
  /// records are then sorted by the full key (insertion sort, or std::sort for a crowded band).
  static void canonicalise(const ImageRegion<Scalar>& image, Workspace& ws) {
    using Record = detail::NodeRecord<Scalar>;
    FrameNodes<Scalar>& nodes = ws.nodes;
    auto less = [](const Record& a, const Record& b) {
      if (a.y != b.y) return a.y < b.y;
      if (a.x != b.x) return a.x < b.x;
      return a.kind < b.kind;
    };
    const std::size_t n = nodes.positions.size();
    // About one band per node, at most one per pixel row.
    const std::size_t bands =
        std::max<std::size_t>(1, std::min(n, static_cast<std::size_t>(std::ceil(image.height_px))));
    const Scalar bands_per_px = static_cast<Scalar>(bands) / image.height_px;
    auto band_of = [&](Scalar y) {
      const Scalar b = (y - image.origin_px.y()) * bands_per_px;  // in [0, bands] for validated nodes
      return std::min(static_cast<std::size_t>(b > 0 ? b : Scalar(0)), bands - 1);
    };
    std::vector<std::uint32_t>& end = ws.band_end;
    end.assign(bands + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++end[band_of(nodes.positions[i].y()) + 1];
    for (std::size_t b = 0; b < bands; ++b) end[b + 1] += end[b];
    Record* records = detail::at_least(ws.records, n);
    for (std::size_t i = 0; i < n; ++i) {
      const Point& p = nodes.positions[i];
      records[end[band_of(p.y())]++] = Record{p.y(), p.x(), nodes.kinds[i]};
    }
    // end[b] is now the end of band b (and the start of band b + 1).
    constexpr std::size_t kInsertionSortMax = 32;
    std::size_t first = 0;
    for (std::size_t b = 0; b < bands; ++b) {
      const std::size_t last = end[b];
      if (last - first > kInsertionSortMax) {
        std::sort(records + first, records + last, less);
      } else {
        for (std::size_t i = first + 1; i < last; ++i) {
          const Record item = records[i];
          std::size_t k = i;
          while (k > first && less(item, records[k - 1])) {
            records[k] = records[k - 1];
            --k;
          }
          records[k] = item;
        }
      }
      first = last;
    }
    nodes.positions.clear();
    nodes.kinds.clear();
    for (std::size_t i = 0; i < n; ++i) {
      const Record& r = records[i];
      const Point p(r.x, r.y);
      if (!nodes.positions.empty() && nodes.positions.back() == p) continue;  // exact duplicate
      nodes.positions.push_back(p);
      nodes.kinds.push_back(r.kind);
    }
  }

  /// The round-based radius search (docs/METHOD.md section 3).
  ///
  /// "Already joined" needs no adjacency lists: an edge is only ever made by one of its endpoints
  /// during its turn as a centre, and a centre leaves its turn joined to every node within the last
  /// radius it tried. So at c's turn, j is joined to c exactly when j has had its turn and c lies
  /// within j's last radius (the same squared-distance comparison, so the test is exact).
  void connect(const ImageRegion<Scalar>& image, const std::vector<Point>& pts, Workspace& ws) const {
    const std::int32_t n = static_cast<std::int32_t>(pts.size());
    const Scalar radius = base_radius(image);
    const Scalar cap = settings.capped_radius_multiple * radius;
    detail::EdgeConstruction& out = ws.construction;
    NeighborSearch& search = ws.search;
    search = neighbor_search;  // the configured prototype; keeps the workspace's storage
    search.build(pts, radius);
    // Squared last radius of each node's turn; -1 until the node has had its turn.
    std::vector<Scalar>& last_rr = ws.last_rr;
    last_rr.assign(static_cast<std::size_t>(n), Scalar(-1));

    // Beyond this radius every node is reachable from any centre, so growing further is pointless.
    Point lo = pts[0], hi = pts[0];
    for (const Point& p : pts) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Scalar span = (hi - lo).norm();

    // v0: the node nearest the image centre; ties go to the lowest canonical index.
    const Point centre = image.centre();
    std::int32_t v0 = 0;
    Scalar best = squared_distance(pts[0], centre);
    for (std::int32_t i = 1; i < n; ++i) {
      const Scalar d = squared_distance(pts[static_cast<std::size_t>(i)], centre);
      if (d < best) {
        best = d;
        v0 = i;
      }
    }
    out.connected[static_cast<std::size_t>(v0)] = 1;

    // Next round's centres as one flag byte per node (a bitmap would chain its read-modify-write
    // updates through one word for neighbouring hits); reading it in order gives them in canonical
    // (ascending) order without a sort.
    std::int32_t* centres = detail::at_least(ws.centres, static_cast<std::size_t>(n));
    centres[0] = v0;
    std::int32_t centre_count = 1;
    std::uint8_t* next_centre = detail::at_least(ws.next_centre, static_cast<std::size_t>(n));
    std::fill(next_centre, next_centre + n, std::uint8_t(0));
    // The hot loop works on local copies: stores through the byte arrays may alias any member, so
    // members would be reloaded after every store.
    std::uint8_t* connected = out.connected.data();
    const Scalar* joined_rr = last_rr.data();
    for (int round = 1; centre_count > 0 && round <= settings.max_rounds; ++round) {
      const bool capped = round >= settings.first_capped_round;
      const std::uint8_t tag = static_cast<std::uint8_t>(std::min(round, 255));
      for (std::int32_t next = 0; next < centre_count; ++next) {
        const std::int32_t c = centres[next];
        Scalar r = radius;  // 2^(t-1) R for attempt t, capped from first_capped_round on
        for (;;) {
          if (capped) r = std::min(r, cap);
          out.reserve_more(static_cast<std::size_t>(n));  // a query yields at most n - 1 edges
          detail::EdgeConstruction::NewEdge* edges = out.edges.get();
          const std::size_t edges_before = out.edge_count;
          std::size_t edge_count = edges_before;
          // Branch-free appends: "already joined" holds about half the time, a branch on it
          // would mispredict constantly. Each write lands in a free slot and the counter
          // advances only when it counts.
          search.for_each_within(c, r, [&](std::int32_t j, Scalar d2) {
            const std::size_t sj = static_cast<std::size_t>(j);
            const bool fresh = !(d2 <= joined_rr[sj]);  // not joined during j's turn
            edges[edge_count] = detail::EdgeConstruction::NewEdge{c < j ? c : j, c < j ? j : c, tag};
            edge_count += static_cast<std::size_t>(fresh);
            const std::uint8_t was = connected[sj];
            next_centre[sj] = static_cast<std::uint8_t>(next_centre[sj] | (fresh & (was == 0)));
            connected[sj] = static_cast<std::uint8_t>(was | static_cast<std::uint8_t>(fresh));
          });
          out.edge_count = edge_count;
          const bool created = edge_count > edges_before;
          const bool stop = created || (capped && r >= cap) || r >= span;
          if (stop) break;  // success; nothing new within the cap; or every node was in reach
          r *= 2;
        }
        last_rr[static_cast<std::size_t>(c)] = r * r;
      }
      centre_count = collect_flags(next_centre, n, centres);
    }
  }

  /// Writes the indices of the non-zero flags to `out` in ascending order, clears the flags and
  /// returns how many there were. Skips eight clear flags at a time; no branch per flag.
  static std::int32_t collect_flags(std::uint8_t* flags, std::int32_t n, std::int32_t* out) {
    std::int32_t count = 0;
    std::int32_t i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t word;
      std::memcpy(&word, flags + i, sizeof word);
      if (!word) continue;
      for (std::int32_t k = i; k < i + 8; ++k) {
        out[count] = k;
        count += flags[k] != 0;
      }
      std::memset(flags + i, 0, 8);
    }
    for (; i < n; ++i) {
      out[count] = i;
      count += flags[i] != 0;
      flags[i] = 0;
    }
    return count;
  }

  /// Joins never-connected nodes, nearest first, each to its nearest node already in the graph
  /// (ties: smaller distance, then lower stray index, then lower target index). Prim-like, exact.
  static void join_strays(const std::vector<Point>& pts, detail::EdgeConstruction& out) {
    const std::int32_t n = static_cast<std::int32_t>(pts.size());
    // Usually the rounds reach every node: then there is nothing to do (and nothing to allocate).
    if (std::find(out.connected.begin(), out.connected.end(), std::uint8_t(0)) == out.connected.end()) return;
    std::vector<std::int32_t> strays;
    std::vector<std::int32_t> members;
    for (std::int32_t i = 0; i < n; ++i) (out.connected[static_cast<std::size_t>(i)] ? members : strays).push_back(i);
    if (strays.empty() || members.empty()) return;
    const Scalar inf = std::numeric_limits<Scalar>::infinity();
    std::vector<Scalar> best_d(strays.size(), inf);
    std::vector<std::int32_t> best_to(strays.size(), -1);
    auto offer = [&](std::size_t s, std::int32_t m) {
      const Scalar d = squared_distance(pts[static_cast<std::size_t>(strays[s])], pts[static_cast<std::size_t>(m)]);
      if (d < best_d[s] || (d == best_d[s] && m < best_to[s])) {
        best_d[s] = d;
        best_to[s] = m;
      }
    };
    for (std::size_t s = 0; s < strays.size(); ++s) {
      for (const std::int32_t m : members) offer(s, m);
    }
    std::vector<std::uint8_t> done(strays.size(), 0);
    for (std::size_t joined = 0; joined < strays.size(); ++joined) {
      std::size_t pick = strays.size();
      for (std::size_t s = 0; s < strays.size(); ++s) {
        if (done[s]) continue;
        if (pick == strays.size() || best_d[s] < best_d[pick]) pick = s;  // strays ascend: ties keep the lower
      }
      done[pick] = 1;
      const std::int32_t a = strays[pick];
      out.append(std::min(a, best_to[pick]), std::max(a, best_to[pick]), kStrayJoin);
      out.connected[static_cast<std::size_t>(a)] = 1;
      for (std::size_t s = 0; s < strays.size(); ++s) {
        if (!done[s]) offer(s, a);
      }
    }
  }

  /// Canonical graph from the edges in creation order without a comparison sort (whose
  /// unpredictable branches cost more than the copies): a counting sort by v, then a stable one
  /// by u, writes the edges in (u, v) order straight into the graph; the CSR rows then fill in
  /// ascending order as in Graph::build_csr (smaller neighbours from the edges by u, larger ones
  /// from each node's own run). No branch depends on the data.
  /// The counting and the first scatter run over two halves of the edges at once: the edges of
  /// one query share an endpoint, and one stream would wait on each counter it just incremented.
  /// Their order within a v bucket does not matter, as the (u, v) pairs are distinct.
  static void to_graph(Workspace& ws, Graph<Scalar>& g) {
    using NewEdge = detail::EdgeConstruction::NewEdge;
    FrameNodes<Scalar>& nodes = ws.nodes;
    const std::int32_t n = static_cast<std::int32_t>(nodes.positions.size());
    const std::size_t nn = static_cast<std::size_t>(n);
    const std::size_t m = ws.construction.edge_count;
    const std::size_t half = m / 2;
    const NewEdge* created = ws.construction.edges.get();
    g.num_nodes_ = n;
    g.weighted_ = true;
    // Bucket starts by v and by u (counts first, shifted by one).
    std::int32_t* start_v = detail::at_least(ws.fill, nn + 1);
    std::int32_t* start_u = detail::at_least(ws.start_u, nn + 1);
    std::fill(start_v, start_v + nn + 1, 0);
    std::fill(start_u, start_u + nn + 1, 0);
    for (std::size_t k = 0; k < half; ++k) {
      const NewEdge& a = created[k];
      const NewEdge& b = created[half + k];
      ++start_v[static_cast<std::size_t>(a.v) + 1];
      ++start_u[static_cast<std::size_t>(a.u) + 1];
      ++start_v[static_cast<std::size_t>(b.v) + 1];
      ++start_u[static_cast<std::size_t>(b.u) + 1];
    }
    if (m % 2) {
      ++start_v[static_cast<std::size_t>(created[m - 1].v) + 1];
      ++start_u[static_cast<std::size_t>(created[m - 1].u) + 1];
    }
    std::vector<std::int32_t>& offsets = g.offsets_;
    offsets.resize(nn + 1);
    offsets[0] = 0;
    for (std::size_t x = 0; x < nn; ++x) {
      offsets[x + 1] = offsets[x] + start_u[x + 1] + start_v[x + 1];  // degree = as u + as v
      start_v[x + 1] += start_v[x];
      start_u[x + 1] += start_u[x];
    }
    if (ws.by_v_capacity < m) {  // uninitialised storage: every slot is written before it is read
      ws.by_v.reset(new NewEdge[m]);
      ws.by_v_capacity = m;
    }
    NewEdge* by_v = ws.by_v.get();
    for (std::size_t k = 0; k < half; ++k) {
      const NewEdge& a = created[k];
      const NewEdge& b = created[half + k];
      by_v[static_cast<std::size_t>(start_v[a.v]++)] = a;
      by_v[static_cast<std::size_t>(start_v[b.v]++)] = b;
    }
    if (m % 2) by_v[static_cast<std::size_t>(start_v[created[m - 1].v]++)] = created[m - 1];
    // Stable by u: (u, v) order, with the pixel lengths. Afterwards start_u[x] is the end of x's run.
    g.edges_.resize(m);
    g.edge_rounds_.resize(m);
    Edge<Scalar>* edges = g.edges_.data();
    std::uint8_t* rounds = g.edge_rounds_.data();
    const Point* pts = nodes.positions.data();
    for (std::size_t k = 0; k < m; ++k) {
      const NewEdge& e = by_v[k];
      const std::size_t at = static_cast<std::size_t>(start_u[e.u]++);
      edges[at] = Edge<Scalar>{e.u, e.v, std::sqrt(squared_distance(pts[e.u], pts[e.v]))};
      rounds[at] = e.round;
    }
    // CSR rows in ascending order: the smaller neighbours of x (edges (u, x), ascending u) first,
    // then its larger ones, which are x's run of edges shifted to the end of its row.
    g.adjacency_.resize(2 * m);
    std::int32_t* adjacency = g.adjacency_.data();
    std::int32_t* fill = start_v;
    std::copy(offsets.begin(), offsets.end() - 1, fill);
    for (std::size_t k = 0; k < m; ++k) adjacency[fill[edges[k].v]++] = edges[k].u;
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t u = static_cast<std::size_t>(edges[k].u);
      adjacency[k + static_cast<std::size_t>(offsets[u + 1] - start_u[u])] = edges[k].v;
    }
    // Swap rather than move, so both the graph and the workspace keep storage for the next build.
    g.positions_.swap(nodes.positions);
    g.kinds_.swap(nodes.kinds);
  }
};

}  // namespace cge
