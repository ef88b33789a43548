// OctoMap side of `cargo xtask eval octomap` (raypath, Khan 2017 ch. 2 comparison).
//
// Usage: octomap-driver <scans.graph> <resolution_m> <beam|endpoint> <queries.txt|-> [out.bt]
//
// Inserts every scan of an OctoMap ScanGraph into an OcTree with the thesis' parameters
// (P_occ 0.7, P_free 0.4, clamping 0.12 / 0.97, threshold 0.5) and prints one JSON object:
// insertion time, node and leaf counts as built and after prune(), memoryUsage(), the time
// to visit the occupied leaves with the leaf iterator, and the classification of the query
// points (one character each: u unknown, f free, o occupied).
//
// beam:     insertPointCloud(scan node, maxrange -1): free cells by ray casting, end points
//           occupied, per-scan de-duplication with occupied winning (OctoMap's own rule).
// endpoint: the end-point cells of each scan, de-duplicated, updated as occupied.
//
// Build: g++ -O2 -std=c++17 driver.cpp -o octomap-driver -loctomap -loctomath

#include <octomap/OcTree.h>
#include <octomap/ScanGraph.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

using namespace octomap;
using Clock = std::chrono::steady_clock;

static double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Peak resident set of this process (VmHWM of /proc/self/status), KiB; 0 when unknown.
static size_t peak_rss_kib() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::strtoull(line.c_str() + 6, nullptr, 10);
  }
  return 0;
}

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s scans.graph resolution beam|endpoint queries.txt|- [out.bt]\n", argv[0]);
    return 2;
  }
  const std::string graph_path = argv[1];
  const double resolution = std::atof(argv[2]);
  const bool beam = std::strcmp(argv[3], "beam") == 0;
  const std::string query_path = argv[4];
  if (!(resolution > 0.0)) {
    std::fprintf(stderr, "bad resolution %s\n", argv[2]);
    return 2;
  }
  ScanGraph graph;
  if (!graph.readBinary(graph_path)) {
    std::fprintf(stderr, "cannot read %s\n", graph_path.c_str());
    return 2;
  }
  OcTree tree(resolution);
  tree.setProbHit(0.7);
  tree.setProbMiss(0.4);
  tree.setClampingThresMin(0.12);
  tree.setClampingThresMax(0.97);
  tree.setOccupancyThres(0.5);

  size_t points = 0;
  auto t0 = Clock::now();
  for (ScanGraph::iterator it = graph.begin(); it != graph.end(); ++it) {
    ScanNode* node = *it;
    points += node->scan->size();
    if (beam) {
      tree.insertPointCloud(*node, -1.0, false, false);
    } else {
      Pointcloud world(*node->scan);
      world.transform(node->pose);
      KeySet occupied;
      for (size_t i = 0; i < world.size(); ++i) {
        OcTreeKey key;
        if (tree.coordToKeyChecked(world[i], key)) occupied.insert(key);
      }
      for (const OcTreeKey& key : occupied) tree.updateNode(key, true, false);
    }
  }
  const double insert_secs = seconds_since(t0);
  const size_t nodes_built = tree.calcNumNodes();
  const size_t leaves_built = tree.getNumLeafNodes();
  auto t1 = Clock::now();
  tree.prune();
  const double prune_secs = seconds_since(t1);
  const size_t nodes = tree.calcNumNodes();
  const size_t leaves = tree.getNumLeafNodes();
  const size_t memory = tree.memoryUsage();

  size_t occupied_leaves = 0;
  size_t visited = 0;
  auto t2 = Clock::now();
  for (OcTree::leaf_iterator it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    ++visited;
    if (tree.isNodeOccupied(*it)) ++occupied_leaves;
  }
  const double access_secs = seconds_since(t2);

  std::string classes;
  if (query_path != "-") {
    std::ifstream in(query_path);
    double x, y, z;
    while (in >> x >> y >> z) {
      OcTreeNode* n = tree.search(point3d(x, y, z));
      classes.push_back(n == nullptr ? 'u' : (tree.isNodeOccupied(n) ? 'o' : 'f'));
    }
  }
  if (argc > 5) tree.writeBinary(argv[5]);

  std::printf(
      "{\"scans\": %zu, \"points\": %zu, \"insert_secs\": %.9f, \"prune_secs\": %.9f, "
      "\"nodes_built\": %zu, \"leaves_built\": %zu, \"nodes\": %zu, \"leaves\": %zu, "
      "\"inner_nodes\": %zu, \"memory_bytes\": %zu, \"occupied_leaves\": %zu, "
      "\"visited_leaves\": %zu, \"access_secs\": %.9f, \"peak_rss_kib\": %zu, "
      "\"classes\": \"%s\"}\n",
      graph.size(), points, insert_secs, prune_secs, nodes_built, leaves_built, nodes, leaves,
      nodes - leaves, memory, occupied_leaves, visited, access_secs, peak_rss_kib(),
      classes.c_str());
  return 0;
}
