#include "solver/additive_schwarz.hpp"

#include <stdexcept>

namespace knotwork {

namespace {

class AdditiveSchwarz final : public Preconditioner {
 public:
  explicit AdditiveSchwarz(std::vector<SchwarzBlock> blocks) : blocks_(std::move(blocks)) {}
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
    z.setZero(r.size());
    Eigen::VectorXd rk, zk;
    for (const SchwarzBlock& b : blocks_) {
      rk.resize(static_cast<Eigen::Index>(b.dofs.size()));
      for (size_t d = 0; d < b.dofs.size(); ++d) rk[static_cast<Eigen::Index>(d)] = b.dofs[d] < 0 ? 0.0 : r[b.dofs[d]];
      b.local->apply(rk, zk);
      for (size_t d = 0; d < b.dofs.size(); ++d)
        if (b.dofs[d] >= 0) z[b.dofs[d]] += zk[static_cast<Eigen::Index>(d)];
    }
  }

 private:
  std::vector<SchwarzBlock> blocks_;
};

}  // namespace

std::unique_ptr<Preconditioner> additive_schwarz(std::vector<SchwarzBlock> blocks, int num_dofs) {
  std::vector<bool> covered(num_dofs, false);
  for (const SchwarzBlock& b : blocks)
    for (int d : b.dofs)
      if (d >= 0) covered.at(d) = true;
  for (int d = 0; d < num_dofs; ++d)
    if (!covered[d]) throw std::invalid_argument("additive_schwarz: dof " + std::to_string(d) + " is in no block");
  return std::make_unique<AdditiveSchwarz>(std::move(blocks));
}

}  // namespace knotwork
