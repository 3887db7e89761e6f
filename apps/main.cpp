// isocharts: the command-line front end. Exit codes: 0 ok, 1 internal failure, 2 bad input.

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <cctype>
#include <functional>
#include <iostream>
#include <memory>
#include <string>

#include "cli.h"
#include "isochart/error.h"
#include "isochart/io.h"

int main(int argc, char** argv) {
  cli::Context ctx;

  CLI::App app{
      "isocharts: stretch-bounded texture atlases (Iso-charts), multi-chart geometry "
      "images and surface texture synthesis"};
  app.set_version_flag("--version", std::string("isocharts ") + ISOCHARTS_VERSION);
  app.require_subcommand(1);
  app.fallthrough();  // global options may follow the subcommand
  app.add_option("--threads", ctx.opts.threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
  app.add_option("--seed", ctx.opts.seed, "Seed for every random choice (results depend only on it)")
      ->check(cli::seed_value);
  CLI::Option* quiet = app.add_flag("-q,--quiet", ctx.opts.quiet, "No warnings or progress on stderr");
  app.add_flag("-v,--verbose", ctx.opts.verbose, "More detail on stderr")->excludes(quiet);
  app.add_flag("--json", ctx.opts.json, "Print the result as one JSON object on stdout");
  app.add_option("--report", ctx.opts.report, "Also save the JSON result to this file");
  app.add_flag("--no-repair", ctx.opts.no_repair,
               "Treat repairable mesh problems (non-manifold, degenerate faces, ...) as errors");
  app.add_flag(
      "--weld", ctx.opts.weld,
      "Join vertices at identical positions (a triangle soup, a mesh split at its UV seams), as for glTF");

  cli::Action action;
  cli::add_info(app, ctx, action);
  cli::add_stats(app, ctx, action);
  cli::add_render(app, ctx, action);
  cli::add_atlas(app, ctx, action);
  cli::add_remesh(app, ctx, action);
  cli::add_psnr(app, ctx, action);
  cli::add_synth(app, ctx, action);
  cli::add_bench(app, ctx, action);
  cli::add_sae(app, ctx, action);

  // An empty value ("--report ''", "--png=") would be taken as "not given" and the output silently
  // skipped; no option or input of ours takes an empty string.
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto eq = arg.find('=');
    if (arg.rfind("--", 0) == 0 && eq != std::string::npos && eq + 1 == arg.size()) {
      std::cerr << "isocharts: error: " << arg.substr(0, eq) << ": expected a value, got ''\n";
      return 2;
    }
    if (!arg.empty()) continue;
    const std::string prev = i > 1 ? argv[i - 1] : "";
    if (prev.size() > 1 && prev[0] == '-' && prev.find('=') == std::string::npos)
      std::cerr << "isocharts: error: " << prev << ": expected a value, got ''\n";
    else
      std::cerr << "isocharts: error: an empty argument was given (argument " << i << ")\n";
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // "A subcommand is required" for `isocharts bogus`: name the word that is not a command.
    if (app.get_subcommands().empty()) {
      std::string names;
      for (const CLI::App* sub : app.get_subcommands({}))
        if (!sub->get_group().empty()) names += (names.empty() ? "" : ", ") + sub->get_name();
      bool command_word = false;
      for (int i = 1; i < argc && !command_word; ++i) {
        const std::string arg = argv[i];
        if (arg == "--threads" || arg == "--seed" || arg == "--report") {
          ++i;  // its value
          continue;
        }
        if (!arg.empty() && arg[0] == '-') continue;
        bool known = false;
        for (const CLI::App* sub : app.get_subcommands({})) known = known || sub->check_name(arg);
        command_word = true;
        if (known) break;  // a command after all: CLI11's own message says what is wrong
        std::cerr << "isocharts: error: unknown command '" << arg << "' (commands: " << names << ")\n";
        return 2;
      }
      if (!command_word && dynamic_cast<const CLI::RequiredError*>(&e)) {
        std::cerr << "isocharts: error: no command given (commands: " << names << "; see isocharts --help)\n";
        return 2;
      }
    }
    std::cerr << "isocharts: error: " << cli::parse_error_message(app, e) << "\n";
    return 2;
  }
  // `--report --threads=2` takes "--threads=2" as the report's file name: the run went on with
  // the default threads and left a file of that name. No value of ours starts with "--".
  {
    std::string bad;
    std::function<void(const CLI::App*)> scan = [&](const CLI::App* a) {
      for (const CLI::Option* o : a->get_options())
        for (const std::string& r : o->results())
          if (bad.empty() && r.size() > 2 && r.compare(0, 2, "--") == 0 &&
              std::isalpha(static_cast<unsigned char>(r[2])))
            bad = o->get_name() + ": got '" + r + "', which is an option, not a value (write ./" + r +
                  " for a file of that name)";
      for (const CLI::App* s : a->get_subcommands()) scan(s);
    };
    scan(&app);
    if (!bad.empty()) {
      std::cerr << "isocharts: error: " << bad << "\n";
      return 2;
    }
  }

  const int threads = ctx.opts.threads > 0 ? ctx.opts.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);

  // Ctrl-C or a kill during a run must not leave the batch's temporary files behind.
  isochart::remove_temporary_files_on_interrupt();
  try {
    // Outputs land together at the end, or not at all when a step fails.
    isochart::OutputBatch outputs;
    action();
    outputs.commit();
  } catch (const isochart::InputError& e) {
    ctx.end_progress();
    std::cerr << "isocharts: error: " << (e.file().empty() ? "" : e.file() + ": ") << e.what() << "\n";
    return 2;
  } catch (const isochart::Cancelled&) {
    ctx.end_progress();
    std::cerr << "isocharts: error: cancelled\n";
    return 1;
  } catch (const std::bad_alloc&) {
    ctx.end_progress();
    std::cerr << "isocharts: error: out of memory\n";
    return 1;
  } catch (const isochart::Error& e) {
    // Thrown on purpose (a failed write, image I/O that cannot be loaded, ...): not a bug.
    ctx.end_progress();
    std::cerr << "isocharts: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    ctx.end_progress();
    std::cerr << "isocharts: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
