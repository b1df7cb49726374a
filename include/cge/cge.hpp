#pragma once
// Umbrella header for the core: graph construction and the combinatorial graph entropy measures.
// Include the individual headers instead when compile time matters.

#include "cge/core/bits.hpp"
#include "cge/core/concepts.hpp"
#include "cge/core/image_region.hpp"
#include "cge/core/mask.hpp"
#include "cge/core/point_traits.hpp"
#include "cge/core/semantic_instance.hpp"
#include "cge/entropy/cge_similarity.hpp"
#include "cge/entropy/coefficients.hpp"
#include "cge/entropy/degree_degree_entropy.hpp"
#include "cge/entropy/exponent_scaling.hpp"
#include "cge/entropy/semantic_prejudgment.hpp"
#include "cge/entropy/shannon_edge_entropy.hpp"
#include "cge/entropy/shortest_path_degree_sums.hpp"
#include "cge/entropy/softmax_entropy.hpp"
#include "cge/graph/graph.hpp"
#include "cge/graph/graph_builder.hpp"
#include "cge/graph/neighbor_search.hpp"
#include "cge/io/graph_text.hpp"
