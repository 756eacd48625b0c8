#include "geometry/quadric_decimation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

namespace u3d {
namespace {

using Vec3d = Eigen::Vector3d;

// Sum of squared distances to a set of planes n.x + d = 0 (area-weighted): x'Ax + 2b.x + c.
struct Quadric {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Vec3d b = Vec3d::Zero();
  double c = 0.0;

  void add_plane(const Vec3d& n, double d, double weight) {
    a += weight * n * n.transpose();
    b += weight * d * n;
    c += weight * d * d;
  }
  Quadric operator+(const Quadric& o) const { return {a + o.a, b + o.b, c + o.c}; }
  double error(const Vec3d& x) const { return x.dot(a * x) + 2.0 * b.dot(x) + c; }
};

// An edge in the queue. The merged vertex's position is computed again when the edge comes up, from
// the same quadrics and positions, as the versions guarantee.
struct Edge {
  int keep, remove;
  int keep_version, remove_version;
};

// A binary min-heap on cost with the costs apart from the edges: sifting (a quarter of the
// decimation's time, mostly cache misses) compares only the costs, a third of the bytes. Pushing and
// popping do exactly what libstdc++'s std::push_heap and std::pop_heap do (the same comparisons, the
// same moves), so edges of equal cost come out in the order std::priority_queue gave them, and the
// decimated meshes are the same.
class CandidateQueue {
 public:
  explicit CandidateQueue(size_t capacity) {
    cost_.reserve(capacity + 1);
    edge_.reserve(capacity);
    cost_.push_back(0.0);  // unused: it puts each pair of siblings in one 16-byte block
  }

  bool empty() const { return edge_.empty(); }

  void push(double cost, const Edge& edge) {
    cost_.push_back(cost);
    edge_.push_back(edge);
    sift_up(edge_.size() - 1, cost, edge);
  }

  // The cheapest edge, taken out.
  Edge pop() {
    const Edge top = edge_[0];
    const size_t len = edge_.size() - 1;
    const double last_cost = key(len);
    const Edge last_edge = edge_[len];
    cost_.pop_back();
    edge_.pop_back();
    if (len > 0) {  // std::__adjust_heap: the hole goes down to a leaf, then the last entry up
      size_t hole = 0, child = 0;
      while (child < (len - 1) / 2) {
        child = 2 * (child + 1);
        if (key(child) > key(child - 1)) --child;
        move(child, hole);
        hole = child;
      }
      if ((len & 1) == 0 && child == (len - 2) / 2) {
        child = 2 * (child + 1) - 1;
        move(child, hole);
        hole = child;
      }
      sift_up(hole, last_cost, last_edge);
    }
    return top;
  }

 private:
  double& key(size_t i) { return cost_[i + 1]; }

  void move(size_t from, size_t to) {
    key(to) = key(from);
    edge_[to] = edge_[from];
  }

  // std::__push_heap: parents costlier than the entry move down into the hole.
  void sift_up(size_t hole, double cost, const Edge& edge) {
    while (hole > 0) {
      const size_t parent = (hole - 1) / 2;
      if (!(key(parent) > cost)) break;
      move(parent, hole);
      hole = parent;
    }
    key(hole) = cost;
    edge_[hole] = edge;
  }

  std::vector<double> cost_;
  std::vector<Edge> edge_;
};

struct Placement {
  Vec3d position;
  double cost;
};

// Flat regions collapse at no cost and would otherwise gather into fans of hundreds of slivers
// around one vertex (slow to update, and poor triangles for the stages after).
constexpr size_t kMaxValence = 16;

// A face whose normal turns by more than this (cosine) or whose area drops to ~0 blocks a collapse.
constexpr double kMinNormalCosine = 0.2;
constexpr double kMinAreaRatio = 1e-6;

class Decimator {
 public:
  // The queue's first candidates are the edges of a closed mesh.
  explicit Decimator(const Mesh& mesh)
      : faces_(mesh.faces), face_alive_(mesh.faces.size(), 1), queue_(mesh.faces.size() * 3 / 2) {
    const size_t nv = mesh.positions.size();
    positions_.reserve(nv);
    for (const Vec3f& p : mesh.positions) positions_.push_back(p.cast<double>());
    quadrics_.resize(nv);
    vertex_faces_.resize(nv);
    version_.assign(nv, 0);
    alive_faces_ = faces_.size();
    for (size_t f = 0; f < faces_.size(); ++f) {
      const Vec3i& t = faces_[f];
      const Vec3d cross = (positions_[t[1]] - positions_[t[0]]).cross(positions_[t[2]] - positions_[t[0]]);
      const double area2 = cross.norm();
      for (int k = 0; k < 3; ++k) vertex_faces_[t[k]].push_back(int(f));
      if (area2 <= 0.0) continue;
      const Vec3d n = cross / area2;
      for (int k = 0; k < 3; ++k) quadrics_[t[k]].add_plane(n, -n.dot(positions_[t[0]]), 0.5 * area2);
    }
    for (const Vec3i& t : faces_)
      for (int k = 0; k < 3; ++k)
        if (t[k] < t[(k + 1) % 3]) push_candidate(t[k], t[(k + 1) % 3]);  // each interior edge once
  }

  void run(size_t target_faces) {
    while (alive_faces_ > target_faces && !queue_.empty()) {
      const Edge e = queue_.pop();
      if (version_[e.keep] != e.keep_version || version_[e.remove] != e.remove_version)
        continue;  // stale: an endpoint moved or vanished since this was computed
      collapse_if_valid(e);
    }
  }

  Mesh result() const {
    Mesh out;
    std::vector<int> new_index(positions_.size(), -1);
    for (size_t f = 0; f < faces_.size(); ++f) {
      if (!face_alive_[f]) continue;
      Vec3i t;
      for (int k = 0; k < 3; ++k) {
        int& id = new_index[faces_[f][k]];
        if (id < 0) {
          id = int(out.positions.size());
          out.positions.push_back(positions_[faces_[f][k]].cast<float>());
        }
        t[k] = id;
      }
      out.faces.push_back(t);
    }
    return out;
  }

 private:
  void push_candidate(int v, int w) {
    queue_.push(std::max(place(v, w).cost, 0.0), {v, w, version_[v], version_[w]});
  }

  // Cheapest point for the merged vertex: the quadric's minimum when well defined, else the best
  // point on the edge (flat regions make the quadric singular).
  Placement place(int v, int w) const {
    const Quadric q = quadrics_[v] + quadrics_[w];
    const Vec3d& pv = positions_[v];
    const Vec3d& pw = positions_[w];
    const Vec3d dir = pw - pv;
    const double curvature = dir.dot(q.a * dir);
    const double t = curvature > 0.0 ? std::clamp(-(pv.dot(q.a * dir) + q.b.dot(dir)) / curvature, 0.0, 1.0) : 0.5;
    Vec3d best = pv + t * dir;
    double cost = q.error(best);
    const double scale = q.a.trace();
    if (std::abs(q.a.determinant()) <= 1e-9 * scale * scale * scale) return {best, cost};  // no minimum (flat)
    Eigen::LDLT<Eigen::Matrix3d> solver(q.a);
    if (solver.info() == Eigen::Success) {
      const Vec3d optimum = solver.solve(-q.b);
      // Trust it only near the edge: far away it is an artefact of an almost singular quadric.
      const double err = q.error(optimum);
      if ((optimum - 0.5 * (pv + pw)).norm() <= dir.norm() && err < cost) best = optimum, cost = err;
    }
    return {best, cost};
  }

  // The faces of v, its list cleared of dead ones on the way.
  const std::vector<int>& live_faces(int v) {
    std::vector<int>& list = vertex_faces_[v];
    list.erase(std::remove_if(list.begin(), list.end(), [&](int f) { return !face_alive_[f]; }), list.end());
    return list;
  }

  static bool has(const Vec3i& t, int v) { return t[0] == v || t[1] == v || t[2] == v; }

  void neighbours(const std::vector<int>& faces, int v, std::vector<int>& out) const {
    out.clear();
    for (int f : faces)
      for (int k = 0; k < 3; ++k)
        if (faces_[f][k] != v) out.push_back(faces_[f][k]);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  Vec3d area_vector(int f) const {
    const Vec3i& t = faces_[f];
    return (positions_[t[1]] - positions_[t[0]]).cross(positions_[t[2]] - positions_[t[0]]);
  }

  // The face with `from` replaced by `to_position` must keep some area and its orientation: against
  // its own normal, and against the neighbourhood's mean normal `around` (the only reference for a
  // face that was degenerate before, whose own normal means nothing).
  bool face_survives_move(int f, int from, const Vec3d& to_position, const Vec3d& around) const {
    const Vec3i& t = faces_[f];
    Vec3d q[3];
    for (int k = 0; k < 3; ++k) q[k] = t[k] == from ? to_position : positions_[t[k]];
    const Vec3d before = area_vector(f), after = (q[1] - q[0]).cross(q[2] - q[0]);
    const double nb = before.norm(), na = after.norm();
    if (na <= kMinAreaRatio * std::max(nb, (q[1] - q[0]).squaredNorm()) || after.dot(around) <= 0.0) return false;
    return nb <= kMinAreaRatio * (q[1] - q[0]).squaredNorm() || before.dot(after) >= kMinNormalCosine * nb * na;
  }

  void collapse_if_valid(const Edge& e) {
    const int keep = e.keep, remove = e.remove;
    // References into the lists: only the collapse itself, at the end, changes them.
    const std::vector<int>& keep_faces = live_faces(keep);
    const std::vector<int>& remove_faces = live_faces(remove);
    shared_.clear();
    for (int f : remove_faces)
      if (has(faces_[f], keep)) shared_.push_back(f);
    if (shared_.size() != 2) return;  // a border or non-manifold edge: left as it is
    // Link condition: the two rings share exactly the two vertices opposite the edge.
    neighbours(keep_faces, keep, keep_ring_);
    neighbours(remove_faces, remove, remove_ring_);
    common_.clear();
    std::set_intersection(keep_ring_.begin(), keep_ring_.end(), remove_ring_.begin(), remove_ring_.end(),
                          std::back_inserter(common_));
    if (common_.size() != 2) return;
    for (int f : shared_)
      for (int k = 0; k < 3; ++k) {
        const int v = faces_[f][k];
        if (v != keep && v != remove && (std::find(common_.begin(), common_.end(), v) == common_.end() ||
                                         live_faces(v).size() <= 3))
          return;  // the opposite vertex would be left with two faces
      }
    if (keep_ring_.size() <= 3 && remove_ring_.size() <= 3) return;  // a tetrahedron: keep it whole
    if (keep_ring_.size() + remove_ring_.size() - 4 > kMaxValence) return;  // merged ring: both lose 2
    const Vec3d position = place(keep, remove).position;
    Vec3d around = Vec3d::Zero();
    for (int f : keep_faces) around += area_vector(f);
    for (int f : remove_faces)
      if (!has(faces_[f], keep)) around += area_vector(f);
    for (int f : keep_faces)
      if (!has(faces_[f], remove) && !face_survives_move(f, keep, position, around)) return;
    for (int f : remove_faces)
      if (!has(faces_[f], keep) && !face_survives_move(f, remove, position, around)) return;

    for (int f : shared_) face_alive_[f] = 0;
    alive_faces_ -= 2;
    for (int f : remove_faces) {  // keep's list grows here, so keep_faces is not used again
      if (!face_alive_[f]) continue;
      for (int k = 0; k < 3; ++k)
        if (faces_[f][k] == remove) faces_[f][k] = keep;
      vertex_faces_[keep].push_back(f);
    }
    ++version_[remove];  // it is in no face any more, so it is never pushed again
    vertex_faces_[remove].clear();
    positions_[keep] = position;
    quadrics_[keep] = quadrics_[keep] + quadrics_[remove];
    ++version_[keep];
    neighbours(live_faces(keep), keep, keep_ring_);
    for (int w : keep_ring_) push_candidate(keep, w);
  }

  std::vector<Vec3d> positions_;
  std::vector<Vec3i> faces_;
  std::vector<char> face_alive_;
  std::vector<Quadric> quadrics_;
  std::vector<std::vector<int>> vertex_faces_;  // may hold dead faces until next visited
  std::vector<int> version_;                    // bumped when a vertex moves, its quadric changes or it goes
  size_t alive_faces_ = 0;
  CandidateQueue queue_;
  std::vector<int> shared_, keep_ring_, remove_ring_, common_;
};

}  // namespace

Mesh decimate_closed_mesh(const Mesh& mesh, size_t target_faces) {
  Decimator decimator(mesh);
  decimator.run(target_faces);
  return decimator.result();
}

}  // namespace u3d
