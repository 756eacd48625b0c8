// `unique3d doctor [--models DIR] [--quick]`: what the networks will run on, and whether the model folder
// holds every network generate needs, each checked (pipeline/doctor.h). Exit status 1 when a network is
// missing or broken.
#include <cstdio>

#include "cli/command.h"
#include "core/error.h"
#include "pipeline/doctor.h"

namespace u3d::cli {
namespace {

struct DoctorArgs {
  std::string models;
  bool quick = false;
};

void print_system(const SystemReport& s) {
  std::printf("cpu      %s, %d hardware threads; AVX-512 kernels: %s; native bf16: %s\n", s.cpu.c_str(), s.cores,
              s.avx512 ? "yes" : "no", s.avx512_bf16 ? "yes" : "no");
  std::printf("threads  %d for the networks (--threads or UNIQUE3D_THREADS to change)\n", s.threads);
  std::printf("libtorch %s; oneDNN: %s; BLAS: %s\n", s.torch_version.c_str(), s.onednn ? "yes" : "no", s.blas.c_str());
  std::printf("dtype    %s by default on this CPU (--dtype to change)\n", s.default_precision.c_str());
  std::printf("cuda     %s\n", s.cuda.c_str());
}

const CommandRegistration registration{
    "doctor", "Check the machine and the model folder: which networks are there, complete and loadable",
    [](CLI::App& sub) {
      auto args = std::make_shared<DoctorArgs>();
      sub.add_option("--models", args->models,
                     "The model folder to check (the official ckpt/ folder; docs/models.md lists its files)");
      sub.add_flag("--quick", args->quick,
                   "Check files, tensor names and shapes and truncation only (about a second per network) instead "
                   "of loading every network (a minute or two, up to ~3.5 GB of memory)");
      return [args] {
        if (args->models.empty()) {
          print_system(system_report());
          std::printf("models   not checked: name the model folder with --models\n");
          return;
        }
        const DoctorReport report =
            run_doctor(args->models, args->quick ? NetworkCheck::kShapes : NetworkCheck::kLoad);
        print_system(report.system);
        std::printf("models   %s (%s)\n", report.models.string().c_str(),
                    args->quick ? "names, shapes and sizes checked" : "every network loaded");
        for (const NetworkCheckResult& r : report.networks) {
          std::printf("  %-7s %-50s %6.1f s   used by: %s\n", r.ok() ? "ok" : "FAILED", network_name(r.network).c_str(),
                      r.seconds, network_users(r.network).c_str());
          if (!r.ok()) std::printf("          %s\n", r.error.c_str());
        }
        const bool matting = report.ok(Network::kMatting);
        if (report.generate_ready())
          std::printf("generate: ready%s\n", matting ? "" : " for photos with a transparent background");
        else if (report.generate_without_refine_ready())
          std::printf("generate: ready with --no-refine only%s\n",
                      matting ? "" : ", for photos with a transparent background");
        else
          std::printf("generate: not ready (see the failures above; docs/models.md says where each file comes from)\n");
        bool all_ok = true;
        for (const NetworkCheckResult& r : report.networks) all_ok = all_ok && r.ok();
        if (!all_ok) throw Error("the model folder " + report.models.string() + " is incomplete or broken (see above)");
      };
    }};

}  // namespace
}  // namespace u3d::cli
