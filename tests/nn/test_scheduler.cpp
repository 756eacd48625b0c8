// Golden case `scheduler` (tests/data/nn/scheduler/case.md): diffusers 0.27.2 schedulers built from
// the SD 1.x config, 30 steps, with recorded model outputs and noise replayed through the step loop.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "core/error.h"
#include "nn/checkpoint/safetensors.h"
#include "nn/schedulers/noise_source.h"
#include "nn/schedulers/scheduler.h"
#include "nn/schedulers/scheduler_euler_ancestral.h"
#include "nn/schedulers/scheduler_sigma_base.h"

namespace fs = std::filesystem;
using namespace u3d::nn;

namespace {

const fs::path kCase = fs::path(UNIQUE3D_TEST_DATA) / "nn" / "scheduler";

const TensorMap& inputs() {
  static const TensorMap m = load_safetensors(kCase / "inputs.safetensors");
  return m;
}
const TensorMap& outputs() {
  static const TensorMap m = load_safetensors(kCase / "outputs.safetensors");
  return m;
}
const torch::Tensor& golden(const std::string& name) {
  auto it = outputs().find(name);
  if (it == outputs().end()) throw std::runtime_error("golden tensor missing: " + name);
  return it->second;
}

// Replays the recorded per-step noise tensors noise.0, noise.1, ... in order.
class ReplayNoise : public NoiseSource {
 public:
  torch::Tensor randn(at::IntArrayRef shape, torch::ScalarType dtype) override {
    const torch::Tensor& n = inputs().at("noise." + std::to_string(next_++));
    EXPECT_EQ(n.sizes(), shape);
    return n.to(dtype);
  }
  int draws() const { return next_; }

 private:
  int next_ = 0;
};

SchedulerConfig traced_config(const std::string& tag) {
  std::ifstream in(kCase / "config.json");
  const auto all = nlohmann::json::parse(in);
  return parse_scheduler_config(all.at(tag), "config.json[" + tag + "]");
}

double max_abs_diff(const torch::Tensor& a, const torch::Tensor& b) {
  return (a.to(torch::kFloat64) - b.to(torch::kFloat64)).abs().max().item<double>();
}

void expect_identical(const torch::Tensor& actual, const torch::Tensor& expected, const std::string& what) {
  ASSERT_EQ(actual.scalar_type(), expected.scalar_type()) << what;
  ASSERT_EQ(actual.sizes(), expected.sizes()) << what;
  EXPECT_TRUE(torch::equal(actual, expected)) << what << ": max diff " << max_abs_diff(actual, expected);
}

// Runs the traced loop and checks tables exactly and every step within 1e-5.
void check_trace(Scheduler& scheduler, const std::string& tag, bool has_sigmas) {
  scheduler.set_timesteps(30);
  expect_identical(scheduler.timesteps(), golden(tag + ".timesteps"), tag + ".timesteps");
  expect_identical(scheduler.alphas_cumprod(), golden(tag + ".alphas_cumprod"), tag + ".alphas_cumprod");
  expect_identical(scheduler.init_noise_sigma(), golden(tag + ".init_noise_sigma"), tag + ".init_noise_sigma");
  if (has_sigmas) {
    auto& sigma_scheduler = dynamic_cast<SigmaScheduler&>(scheduler);
    expect_identical(sigma_scheduler.sigmas(), golden(tag + ".sigmas"), tag + ".sigmas");
  }

  ReplayNoise noise;
  torch::Tensor sample = inputs().at("init_noise") * scheduler.init_noise_sigma();
  double worst = 0;
  for (int i = 0; i < scheduler.num_steps(); ++i) {
    const std::string prefix = tag + ".step" + std::to_string(i) + ".";
    const torch::Tensor scaled = scheduler.scale_model_input(sample, i);
    const SchedulerStep out = scheduler.step(inputs().at("model_output." + std::to_string(i)), i, sample, noise);
    for (const auto& [name, value] : {std::pair{"scaled_model_input", scaled},
                                      {"prev_sample", out.prev_sample},
                                      {"pred_original_sample", out.pred_original_sample}}) {
      const double err = max_abs_diff(value, golden(prefix + name));
      EXPECT_LE(err, 1e-5) << prefix << name;
      worst = std::max(worst, err);
    }
    sample = out.prev_sample;
  }
  EXPECT_LE(max_abs_diff(sample, golden(tag + ".final_sample")), 1e-5) << tag;
  std::cout << "[ trace    ] " << tag << ": worst step error " << worst << "\n";
}

}  // namespace

TEST(Scheduler, EulerAncestralLinspaceMatchesGolden) {
  auto s = make_scheduler(traced_config("euler_a_linspace"));
  check_trace(*s, "euler_a_linspace", true);
}

TEST(Scheduler, EulerAncestralLeadingMatchesGolden) {
  auto s = make_scheduler(traced_config("euler_a_leading"));
  check_trace(*s, "euler_a_leading", true);
}

TEST(Scheduler, EulerAncestralTrailingMatchesGolden) {
  auto s = make_scheduler(traced_config("euler_a_trailing"));
  check_trace(*s, "euler_a_trailing", true);
}

TEST(Scheduler, EulerMatchesGolden) {
  auto s = make_scheduler(traced_config("euler"));
  check_trace(*s, "euler", true);
}

TEST(Scheduler, DdimMatchesGolden) {
  auto s = make_scheduler(traced_config("ddim"));
  check_trace(*s, "ddim", false);
}

// What Unique3D does: the sd-image-variations PNDM config loaded into EulerAncestral, whose default
// spacing (linspace) applies because the config has no timestep_spacing.
TEST(Scheduler, PndmConfigIntoEulerAncestralUsesLinspace) {
  const SchedulerConfig config = read_scheduler_config(kCase / "sd_scheduler_config.json");
  EXPECT_EQ(config.class_name, "PNDMScheduler");
  EXPECT_FALSE(config.timestep_spacing.has_value());
  EXPECT_THROW(make_scheduler(config), u3d::Error);  // PNDM itself is not implemented
  auto s = make_scheduler(config, SchedulerKind::EulerAncestral);
  check_trace(*s, "euler_a_linspace", true);
}

TEST(Scheduler, AncestralStepDrawsOneNoisePerStep) {
  auto s = make_scheduler(traced_config("euler_a_linspace"));
  s->set_timesteps(30);
  ReplayNoise noise;
  torch::Tensor sample = inputs().at("init_noise");
  for (int i = 0; i < 3; ++i) sample = s->step(inputs().at("model_output." + std::to_string(i)), i, sample, noise).prev_sample;
  EXPECT_EQ(noise.draws(), 3);
}

TEST(Scheduler, SeededNoiseIsReproducible) {
  SeededNoise a(42), b(42), c(43);
  const torch::Tensor x = a.randn({1, 4, 8, 8});
  EXPECT_TRUE(torch::equal(x, b.randn({1, 4, 8, 8})));
  EXPECT_FALSE(torch::equal(x, c.randn({1, 4, 8, 8})));
  EXPECT_FALSE(torch::equal(x, a.randn({1, 4, 8, 8})));  // the stream advances
  EXPECT_NEAR(SeededNoise(0).randn({100000}).std().item<double>(), 1.0, 0.02);
}

TEST(Scheduler, RefusesBadConfigsAndCalls) {
  auto config_with = [](const char* key, nlohmann::json value) {
    nlohmann::json j = {{"_class_name", "EulerAncestralDiscreteScheduler"}};
    j[key] = value;
    return parse_scheduler_config(j, "test_config.json");
  };
  auto expect_error = [](auto&& f, const std::string& fragment) {
    try {
      f();
      ADD_FAILURE() << "no error, expected one mentioning " << fragment;
    } catch (const u3d::Error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  expect_error([&] { config_with("beta_start", "small"); }, "beta_start");
  expect_error([&] { make_scheduler(config_with("timestep_spacing", "sideways")); }, "sideways");
  expect_error([&] { make_scheduler(config_with("beta_schedule", "exotic")); }, "exotic");
  expect_error([&] { make_scheduler(config_with("use_karras_sigmas", true)); }, "use_karras_sigmas");
  expect_error([&] { make_scheduler(config_with("prediction_type", "sample")); }, "prediction_type");
  expect_error([&] { read_scheduler_config(kCase / "no_such_config.json"); }, "no_such_config.json");

  auto s = make_scheduler(config_with("num_train_timesteps", 1000));
  expect_error([&] { s->scale_model_input(torch::zeros({1}), 0); }, "set_timesteps");
  s->set_timesteps(10);
  expect_error([&] { s->scale_model_input(torch::zeros({1}), 10); }, "step index 10");
  expect_error([&] { s->set_timesteps(1001); }, "1001");
}
