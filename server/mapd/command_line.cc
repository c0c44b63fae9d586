#include "mapd/command_line.h"

#include "mapd/migrate_command.h"
#include "mapd/token_command.h"
#include "service/config_settings.h"

namespace mapd {

void AddFlags(CLI::App* app, CommandLine* line) {
  using service::Setting;
  // A flag given twice: the later one wins (the container entrypoint passes its
  // defaults first, the user's flags after them). Subcommands inherit this.
  app->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app->footer(
      "Every KEY may also be set in the config file as 'KEY = VALUE'; flags override the file.");
  app->add_option("--config", line->config_files, "read settings from FILE first")
      ->type_name("FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app->add_flag("--print-config", line->print_config,
                "print the settings in effect as a config file, and exit");
  app->add_flag("--version", line->version, "print the version and exit");
  const service::ServerConfig defaults;
  for (const Setting& s : service::Settings()) {
    // --data-dir as the issue and docs spell it, beside the setting's name.
    const std::string names = "--" + s.key + (s.key == "data_dir" ? ",--data-dir" : "");
    app->add_option_function<std::string>(
           names,
           [line, key = s.key](const std::string& v) { line->settings.emplace_back(key, v); },
           s.help)
        ->type_name("<" + s.kind + ">")
        ->default_str(s.get(defaults));
  }
  AddTokenCommand(app, &line->offline);
  AddMigrateCommand(app, &line->offline);
}

Status ApplyCommandLine(const CommandLine& line, service::ServerConfig* config) {
  for (const std::string& file : line.config_files)
    MAPD_RETURN_IF_ERROR(service::LoadConfigFile(file, config));
  for (const auto& [key, value] : line.settings)
    MAPD_RETURN_IF_ERROR(service::ApplySetting(key, value, config));
  return config->Validate();
}

}  // namespace mapd
