// A study with one driven trial and its experimenter's console on a free
// port, for the browser test (console_browser.py): prints "url URL" and
// "db FILE", then serves until its standard input closes.
#include <cstdio>
#include <iostream>
#include <string>

#include "haptel/config/paths.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/console.hpp"
#include "study_test_run.hpp"

using namespace haptel;
using namespace haptel::study;

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: study_console_fixture DIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  StudyConfig config;
  config.file = dir / "browser.yaml";
  {
    std::FILE* f = std::fopen(config.file.c_str(), "w");
    std::fputs("name: browser\n", f);
    std::fclose(f);
  }
  config.name = "browser";
  config.conditions = {{"cockpit", "cockpit"}, {"gesture", "gesture"}};
  config.participants = {{"A", ""}};
  config.questionnaires = {"thesis", "rating"};
  config.demographics = "demographics";
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1}, {"A", 2, "cockpit", 1}};
  const std::filesystem::path db = dir / "browser.db";
  std::filesystem::remove(db);
  {
    record::Recorder recorder(db);
    StudyStore store(recorder, config, plan);
    recorder.Save(test::TrialRun(18.25), store.TrialWriter(plan[0], 600.0));
  }
  const std::filesystem::path shipped = ShippedFile("config/questionnaires");
  const std::map<std::string, Questionnaire> questionnaires = {
      {"thesis", FindQuestionnaire(shipped, "thesis")},
      {"rating", FindQuestionnaire(shipped, "rating")},
      {"demographics", FindQuestionnaire(shipped, "demographics")}};
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, plan, db, questionnaires, options);
  std::printf("url %s\ndb %s\n", console.url().c_str(), db.c_str());
  std::fflush(stdout);
  std::string line;
  while (std::getline(std::cin, line)) {
  }
  return 0;
}
