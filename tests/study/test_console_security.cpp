// The experimenter's console defends itself as a web application, through
// real HTTP against the real console: a page of another site (cross-site
// posts, a forged Host) changes and reads nothing; bodies are bounded before
// they are read and the limits count characters; slow clients neither stall
// it nor hold it; beyond loopback the page asks once for an access token;
// HTTPS with a certificate.
#include <httplib.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>
#include <vector>

#include "console_client.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/link/security.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/console.hpp"
#include "haptel/study/console_access.hpp"
#include "study_test_run.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

/// A person study with participant A's first trial driven, and its console.
struct Study {
  std::filesystem::path dir;
  StudyConfig config;
  std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1}, {"A", 2, "cockpit", 1}};
  std::filesystem::path db;
  std::map<std::string, Questionnaire> questionnaires;

  explicit Study(const std::string& name) : dir(test::ScratchDir(name)), db(dir / "s.db") {
    config.file = test::WriteFile(dir / "s.yaml", "name: s\n");
    config.name = name;
    config.operators = "person";
    config.conditions = {{"cockpit", "cockpit"}, {"gesture", "gesture"}};
    config.participants = {{"A", ""}};
    config.questionnaires = {"thesis"};
    questionnaires = {
        {"thesis", FindQuestionnaire(ShippedFile("config/questionnaires"), "thesis")}};
    record::Recorder recorder(db);
    StudyStore store(recorder, config, plan);
    recorder.Save(test::TrialRun(21.5), store.TrialWriter(plan[0], 600.0));
  }
  size_t Trials() const {
    record::Recorder recorder(db);
    return StudyStore(recorder, config, plan).Trials().size();
  }
  size_t Participants() const {
    record::Recorder recorder(db);
    return StudyStore(recorder, config, plan).Participants().size();
  }
  size_t Answers() const {
    record::Recorder recorder(db);
    return StudyStore(recorder, config, plan).Answers().size();
  }
};

/// One raw exchange: `request` sent as is, the whole answer.
std::string Exchange(int port, const std::string& request, const std::string& from = "127.0.0.1") {
  const int fd = test::ConnectFrom(from, port);
  if (fd < 0) return "";
  test::SendAll(fd, request);
  std::string answer = test::ReadUntilClosed(fd);
  close(fd);
  return answer;
}

std::string StatusLine(const std::string& answer) { return answer.substr(0, answer.find("\r\n")); }

}  // namespace

TEST_CASE("A page of another site, or a forged Host, neither changes the study nor reads it") {
  Study study("console-cross-site");
  ConsoleOptions options;
  options.port = 0;
  options.thumbnail = true;
  StudyConsole console(study.config, study.plan, study.db, study.questionnaires, options);
  console.SetPicture({0xFF, 0xD8, 0xFF, 0xD9}, 1);
  test::ConsoleClient page("127.0.0.1", console.port());
  const std::string token = page.token();
  REQUIRE(token.size() == 32);
  const std::string own = "http://127.0.0.1:" + std::to_string(console.port());

  SECTION("a cross-site form post is refused with a reason and changes nothing") {
    const httplib::Params redo = {{"participant", "A"}, {"position", "1"}, {"csrf", token}};
    const auto evil = page.raw().Post("/redo", {{"Origin", "http://evil.example"}}, redo);
    REQUIRE(evil);
    CHECK(evil->status == 403);
    CHECK(evil->body.find("another site (http://evil.example)") != std::string::npos);
    const auto fetch = page.raw().Post("/redo", {{"Sec-Fetch-Site", "cross-site"}}, redo);
    REQUIRE(fetch);
    CHECK(fetch->status == 403);
    CHECK(fetch->body.find("Sec-Fetch-Site: cross-site") != std::string::npos);
    const auto null_origin = page.raw().Post("/redo", {{"Origin", "null"}}, redo);
    REQUIRE(null_origin);
    CHECK(null_origin->status == 403);
    // A browser that sends neither header: the form token stops it.
    const auto no_token =
        page.raw().Post("/redo", httplib::Params{{"participant", "A"}, {"position", "1"}});
    REQUIRE(no_token);
    CHECK(no_token->status == 403);
    CHECK(no_token->body.find("not one this console served") != std::string::npos);
    const auto wrong_token = page.raw().Post(
        "/redo",
        httplib::Params{{"participant", "A"}, {"position", "1"}, {"csrf", std::string(32, '0')}});
    REQUIRE(wrong_token);
    CHECK(wrong_token->status == 403);
    const auto add = page.raw().Post("/participants", {{"Origin", "http://evil.example"}},
                                     httplib::Params{{"id", "P9"}, {"csrf", token}});
    REQUIRE(add);
    CHECK(add->status == 403);
    const auto abort = page.raw().Post("/abort", {{"Sec-Fetch-Site", "same-site"}},
                                       httplib::Params{{"csrf", token}});
    REQUIRE(abort);
    CHECK(abort->status == 403);
    CHECK(study.Trials() == 1);
    CHECK(study.Participants() == 1);
    CHECK_FALSE(console.abort_requested().load());
    CHECK(console.connection_counters().refused_requests >= 7);

    // The console's own page, as the browser sends it, does what it says.
    const auto same =
        page.raw().Post("/redo", {{"Origin", own}, {"Sec-Fetch-Site", "same-origin"}}, redo);
    REQUIRE(same);
    CHECK(same->status == 303);
    CHECK(study.Trials() == 0);
  }

  SECTION("another Host is refused: a rebound DNS name reads neither the schedule nor the camera") {
    for (const std::string path :
         {"/", "/video.jpg", "/status.json", "/questionnaire?name=thesis"}) {
      const std::string answer = Exchange(
          console.port(), "GET " + path + " HTTP/1.1\r\nHost: evil.example:" +
                              std::to_string(console.port()) + "\r\nConnection: close\r\n\r\n");
      CAPTURE(path, answer.substr(0, 200));
      CHECK(StatusLine(answer) == "HTTP/1.1 403 Forbidden");
      CHECK(answer.find("does not answer to Host") != std::string::npos);
      CHECK(answer.find("console-cross-site") ==
            std::string::npos);  // the study's name is not in it
      CHECK(answer.find("\xFF\xD8") == std::string::npos);
    }
    const std::string nameless = Exchange(console.port(), "GET / HTTP/1.0\r\n\r\n");
    CHECK(StatusLine(nameless).find("403") != std::string::npos);
    // The console's own names are answered, and its pages may not be framed.
    for (const std::string host : {"127.0.0.1", "localhost", "LOCALHOST"}) {
      const std::string answer = Exchange(console.port(), "GET / HTTP/1.1\r\nHost: " + host + ":" +
                                                              std::to_string(console.port()) +
                                                              "\r\nConnection: close\r\n\r\n");
      CAPTURE(host);
      CHECK(StatusLine(answer) == "HTTP/1.1 200 OK");
      CHECK(answer.find("X-Frame-Options: DENY") != std::string::npos);
    }
  }
}

TEST_CASE("Bodies are bounded before they are read, and the limits count characters, not bytes") {
  Study study("console-bodies");
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(study.config, study.plan, study.db, study.questionnaires, options);
  test::ConsoleClient page("127.0.0.1", console.port());
  const std::string host = "Host: 127.0.0.1:" + std::to_string(console.port()) + "\r\n";

  SECTION("a 1 GiB form is refused from its head, with a reason, without its body being sent") {
    const std::string answer = Exchange(
        console.port(), "POST /answers HTTP/1.1\r\n" + host +
                            "Content-Type: application/x-www-form-urlencoded\r\n"
                            "Content-Length: 1073741824\r\nConnection: close\r\n\r\nparticipant=A");
    CHECK(StatusLine(answer) == "HTTP/1.1 413 Payload Too Large");
    CHECK(answer.find("the form is 1073741824 bytes") != std::string::npos);
    const std::string other =
        Exchange(console.port(), "POST /participants HTTP/1.1\r\n" + host +
                                     "Content-Type: application/x-www-form-urlencoded\r\n"
                                     "Content-Length: 100000\r\nConnection: close\r\n\r\nid=");
    CHECK(StatusLine(other) == "HTTP/1.1 413 Payload Too Large");
  }

  SECTION("a chunked body with no length stops at the limit") {
    const std::string chunk(60000, 'x');
    std::string request =
        "POST /answers HTTP/1.1\r\n" + host +
        "Content-Type: application/x-www-form-urlencoded\r\nTransfer-Encoding: chunked\r\n"
        "Connection: close\r\n\r\n";
    char size[32];
    std::snprintf(size, sizeof size, "%zx\r\n", chunk.size());
    for (int i = 0; i < 20; ++i) request += size + chunk + "\r\n";
    request += "0\r\n\r\n";
    const std::string answer = Exchange(console.port(), request);
    CHECK(StatusLine(answer).find("413") != std::string::npos);
    CHECK(study.Answers() == 0);
  }

  SECTION(
      "a chunked body, or one with no length, to a short form's route is refused from its head") {
    // 256 kB of chunks, with no last chunk: a console that reads the body
    // takes them all and waits for more (the attack's 1 GiB was read whole).
    std::string chunks;
    const std::string chunk(4096, 'x');
    for (int i = 0; i < 64; ++i) chunks += "1000\r\n" + chunk + "\r\n";
    for (const char* path : {"/participants", "/redo", "/start"}) {
      CAPTURE(path);
      const std::string head = std::string("POST ") + path + " HTTP/1.1\r\n" + host +
                               "Content-Type: application/x-www-form-urlencoded\r\n";
      const std::string chunked =
          Exchange(console.port(),
                   head + "Transfer-Encoding: chunked\r\nConnection: close\r\n\r\n" + chunks);
      CHECK(StatusLine(chunked) == "HTTP/1.1 411 Length Required");
      CHECK(chunked.find("Content-Length") != std::string::npos);
      // Both headers: the library would read the chunks, not the length.
      const std::string both = Exchange(
          console.port(),
          head + "Content-Length: 10\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n\r\n" +
              chunks);
      CHECK(StatusLine(both) == "HTTP/1.1 411 Length Required");
      // No length at all: the library would read until the client closes.
      const std::string unbounded =
          Exchange(console.port(), head + "Connection: close\r\n\r\n" + chunk);
      CHECK(StatusLine(unbounded) == "HTTP/1.1 411 Length Required");
    }
    CHECK(study.Participants() == 1);
    // The routes that read their form themselves stop a chunked body at their limit.
    const std::string note =
        Exchange(console.port(), "POST /notes HTTP/1.1\r\n" + host +
                                     "Content-Type: application/x-www-form-urlencoded\r\n"
                                     "Transfer-Encoding: chunked\r\nConnection: close\r\n\r\n" +
                                     chunks);
    CHECK(StatusLine(note) == "HTTP/1.1 413 Payload Too Large");
  }

  SECTION("a request far larger than any form is cut as it streams, whatever it claims") {
    // A header line of 64 MiB reaches no handler: the connection's bytes are
    // bounded below, so the console stops reading long before the end.
    const int fd = test::ConnectFrom("127.0.0.1", console.port());
    REQUIRE(fd >= 0);
    const std::string line = "GET / HTTP/1.1\r\n" + host + "X-Long: " + std::string(64 << 20, 'x');
    const bool all_sent = test::SendAll(fd, line);
    close(fd);
    CHECK_FALSE(all_sent);
  }

  SECTION(
      "a remark of 1 000 CJK characters is taken; one past the item's 2 000 characters is refused "
      "saying so") {
    std::string cjk;
    for (int i = 0; i < 1000; ++i)
      cjk += "\xE6\xBC\xA2";  // U+6F22, 3 bytes of UTF-8, 9 once url-encoded
    const auto taken = page.Post("/answers", {{"participant", "A"},
                                              {"condition", "gesture"},
                                              {"questionnaire", "thesis"},
                                              {"easy_to_learn", "4"},
                                              {"efficient", "5"},
                                              {"remarks", cjk}});
    REQUIRE(taken);
    CHECK(taken->status == 200);
    CHECK(study.Answers() == 3);

    // 2 000 characters of 4 bytes each (the most a character takes) fit the
    // console's body limit: the item's limit decides, in characters.
    Study other("console-bodies-long");
    StudyConsole second(other.config, other.plan, other.db, other.questionnaires, options);
    test::ConsoleClient page2("127.0.0.1", second.port());
    std::string widest;
    for (int i = 0; i < 2000; ++i) widest += "\xF0\x9F\x98\x80";  // U+1F600
    const httplib::Params form = {{"participant", "A"},
                                  {"condition", "gesture"},
                                  {"questionnaire", "thesis"},
                                  {"easy_to_learn", "4"},
                                  {"efficient", "5"}};
    httplib::Params too_long = form;
    too_long.emplace("remarks", widest + "x");
    const auto refused = page2.Post("/answers", too_long);
    REQUIRE(refused);
    CHECK(refused->status == 422);
    CHECK(refused->body.find("at most 2000 characters, got 2001") != std::string::npos);
    httplib::Params longest = form;
    longest.emplace("remarks", widest);
    const auto accepted = page2.Post("/answers", longest);
    REQUIRE(accepted);
    CHECK(accepted->status == 200);
    CHECK(other.Answers() == 3);
  }
}

TEST_CASE("Slow clients neither stall the console nor hold its connections") {
  Study study("console-slow");
  ConsoleOptions options;
  options.port = 0;
  options.connections.max_per_client = 4;
  options.connections.threads = 8;
  options.connections.head_deadline = std::chrono::milliseconds(1500);
  options.connections.deadline = std::chrono::milliseconds(1500);
  options.connections.idle = std::chrono::milliseconds(1000);
  StudyConsole console(study.config, study.plan, study.db, study.questionnaires, options);
  const int port = console.port();

  // Ten connections from another address, each sending a header line every
  // 0.3 s, as the attack did (every 2 s there), for up to 30 lines.
  constexpr int kSlow = 10;
  constexpr int kLines = 30;
  std::vector<int> lines_sent(kSlow, 0);
  std::vector<std::string> answers(kSlow);
  std::atomic<int> connected{0};
  std::vector<std::thread> slow;
  for (int i = 0; i < kSlow; ++i) {
    slow.emplace_back([&, i] {
      const int fd = test::ConnectFrom("127.0.0.2", port);
      if (fd < 0) return;
      ++connected;
      test::SendAll(fd, "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n");
      for (int line = 0; line < kLines; ++line) {
        pollfd p{fd, POLLIN, 0};
        if (poll(&p, 1, 300) > 0) break;  // the server answered or closed
        if (!test::SendAll(fd, "X-Slow-" + std::to_string(line) + ": 1\r\n")) break;
        lines_sent[i] = line + 1;
      }
      answers[i] = test::ReadUntilClosed(fd);
      close(fd);
    });
  }
  while (connected.load() < kSlow) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));

  // The experimenter's page is answered meanwhile.
  test::ConsoleClient page("127.0.0.1", port);
  const auto schedule = page.Get("/");
  REQUIRE(schedule);
  CHECK(schedule->status == 200);
  CHECK(schedule->body.find("1 of 2 trials done") != std::string::npos);

  for (std::thread& t : slow) t.join();
  // Every slow connection was ended by the console long before its 30
  // lines: beyond four from one address the oldest are cut for the newer,
  // the others at the head's deadline; none is refused (there is always one
  // to cut: none has sent its head).
  for (int i = 0; i < kSlow; ++i) {
    CAPTURE(i, lines_sent[i]);
    CHECK(lines_sent[i] < kLines);
  }
  const ConnectionCounters counters = console.connection_counters();
  CHECK(counters.refused_busy == 0);
  CHECK(counters.cut_for_room >= 1);
  CHECK(counters.cut_deadline >= 1);
}

TEST_CASE(
    "A hundred slow connections, from the experimenter's address and others, do not keep the page "
    "from them") {
  Study study("console-slowloris");
  ConsoleOptions options;  // the defaults: what `haptel study run` serves with
  options.port = 0;
  StudyConsole console(study.config, study.plan, study.db, study.questionnaires, options);
  const int port = console.port();
  const std::string partial =
      "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nX-Slow: ";

  // 40 from 127.0.0.1 (the experimenter's own address), 3 from each of
  // 127.0.0.2..21; every other one dribbles a partial request a byte at a
  // time, the rest send nothing. One the console closes is opened again.
  struct Slow {
    std::string from;
    bool dribble = false;
    int fd = -1;
    size_t sent = 0;
  };
  std::vector<Slow> slow;
  for (int i = 0; i < 100; ++i) {
    slow.push_back(
        {i < 40 ? "127.0.0.1" : "127.0.0." + std::to_string(2 + (i - 40) / 3), i % 2 == 0});
  }
  std::atomic<bool> stop{false};
  std::atomic<int> opened{0};
  std::thread attacker([&] {
    while (!stop.load()) {
      for (Slow& s : slow) {
        if (s.fd < 0) {
          s.fd = test::ConnectFrom(s.from, port);
          s.sent = 0;
          if (s.fd >= 0) ++opened;
          continue;
        }
        pollfd p{s.fd, POLLIN, 0};
        if (poll(&p, 1, 0) > 0) {  // answered or closed by the console: open another
          close(s.fd);
          s.fd = -1;
          continue;
        }
        if (s.dribble) {
          const char byte = s.sent < partial.size() ? partial[s.sent] : 'x';
          if (send(s.fd, &byte, 1, MSG_NOSIGNAL | MSG_DONTWAIT) == 1) ++s.sent;
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    for (Slow& s : slow) {
      if (s.fd >= 0) close(s.fd);
    }
  });
  REQUIRE(test::WaitFor([&] { return opened.load() >= 100; }, 30.0));

  // The experimenter's page, from their own address and from another, while
  // the hundred hold on (each request waits at most 10 s, far more than it needs).
  int answered = 0;
  for (int i = 0; i < 6; ++i) {
    const std::string from = i % 2 == 0 ? "127.0.0.1" : "127.0.0.99";
    const int fd = test::ConnectFrom(from, port);
    CAPTURE(i, from);
    REQUIRE(fd >= 0);
    timeval wait{10, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &wait, sizeof wait);
    test::SendAll(fd, "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                          "\r\nConnection: close\r\n\r\n");
    const std::string answer = test::ReadUntilClosed(fd);
    close(fd);
    CHECK(StatusLine(answer) == "HTTP/1.1 200 OK");
    answered += answer.find("1 of 2 trials done") != std::string::npos;
  }
  stop.store(true);
  attacker.join();
  CHECK(answered == 6);
  const ConnectionCounters counters = console.connection_counters();
  CAPTURE(counters.served, counters.refused_busy, counters.cut_deadline);
  CHECK(counters.refused_busy == 0);
}

/// The test process's threads now (/proc/self/status).
int ProcessThreads() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  }
  return -1;
}

TEST_CASE("The console's workers come with its connections and go when idle") {
  // A study's trial locks the process's memory for its servo loop, every
  // thread's stack with it: idle workers are a study's resident memory.
  Study study("console-workers");
  ConsoleOptions options;  // the defaults (128 workers at most), but a short linger
  options.port = 0;
  options.connections.worker_linger = std::chrono::milliseconds(100);
  // Silent connections hold their workers until closed here, however slowly
  // a loaded machine accepts them.
  options.connections.head_deadline = std::chrono::seconds(60);
  options.connections.deadline = std::chrono::seconds(60);
  options.connections.idle = std::chrono::seconds(60);
  const int before = ProcessThreads();
  StudyConsole console(study.config, study.plan, study.db, study.questionnaires, options);
  const int port = console.port();
  const std::string get =
      "GET /status.json HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n";

  // A page's requests one after another: a worker or two, not the pool's 128.
  for (int i = 0; i < 40; ++i) REQUIRE(StatusLine(Exchange(port, get)) == "HTTP/1.1 200 OK");
  CHECK(console.connection_counters().workers <= 8);
  CHECK(ProcessThreads() - before <= 10);  // the listener and the workers

  // Twenty connections at once (from as many addresses) that send nothing:
  // a worker each, ...
  std::vector<int> silent;
  for (int i = 0; i < 20; ++i)
    silent.push_back(test::ConnectFrom("127.0.0." + std::to_string(2 + i), port));
  REQUIRE(test::WaitFor([&] { return console.connection_counters().workers >= 20; }, 60.0));
  // ... closed here; then idle, they end.
  for (const int fd : silent) close(fd);
  // Bounds a hang; asserts no timing.
  CHECK(test::WaitFor([&] { return console.connection_counters().workers == 0; }, 30.0));
  CHECK(test::WaitFor([&] { return ProcessThreads() - before <= 1; }, 30.0));
  CHECK(StatusLine(Exchange(port, get)) == "HTTP/1.1 200 OK");
}

TEST_CASE("Beyond loopback the console asks once for its access token") {
  Study study("console-token");
  ConsoleOptions options;
  options.port = 0;
  options.host = "0.0.0.0";

  SECTION("bound to every interface, it names addresses a browser can open, not 0.0.0.0") {
    ConsoleOptions every;
    every.port = 0;
    every.host = "0.0.0.0";
    every.plain_http = true;
    StudyConsole console(study.config, study.plan, study.db, study.questionnaires, every);
    const std::string loopback = "http://127.0.0.1:" + std::to_string(console.port()) + "/";
    CAPTURE(console.url());
    CHECK(console.url().find("0.0.0.0") == std::string::npos);
    CHECK(console.url().rfind("http://", 0) == 0);
    const auto urls = ConsoleUrls("0.0.0.0", console.port(), false, {});
    CHECK(std::find(urls.begin(), urls.end(), loopback) != urls.end());
    for (const std::string& url : urls) CHECK(url.find("0.0.0.0") == std::string::npos);
    // Bound to one address, that address.
    CHECK(ConsoleUrls("127.0.0.1", 8470, false, {}) ==
          std::vector<std::string>{"http://127.0.0.1:8470/"});
    CHECK(ConsoleUrls("0.0.0.0", 8470, true, {"console.test"}) ==
          std::vector<std::string>{"https://console.test:8470/"});
  }

  SECTION("without HTTPS it is refused unless plain HTTP is asked for") {
    CHECK_THROWS_WITH(
        StudyConsole(study.config, study.plan, study.db, study.questionnaires, options),
        Catch::Contains("haptel security init") && Catch::Contains("--plain-http"));
  }

  SECTION("the page asks for the token, then a cookie holds it") {
    options.plain_http = true;
    options.access_token = "0123456789abcdef0123456789abcdef";
    StudyConsole console(study.config, study.plan, study.db, study.questionnaires, options);
    CHECK(console.access_token() == options.access_token);
    test::ConsoleClient page("127.0.0.1", console.port());
    const auto asked = page.Get("/");
    REQUIRE(asked);
    CHECK(asked->status == 401);
    CHECK(asked->body.find("id=\"token\"") != std::string::npos);
    CHECK(asked->body.find("1 of 2 trials") == std::string::npos);
    const auto picture = page.Get("/video.jpg");
    REQUIRE(picture);
    CHECK(picture->status == 401);
    const auto answers = page.Post("/redo", {{"participant", "A"}, {"position", "1"}});
    REQUIRE(answers);
    CHECK(answers->status == 401);
    CHECK(study.Trials() == 1);

    const auto wrong = page.Post("/login", {{"token", "0123456789abcdef0123456789abcdee"}});
    REQUIRE(wrong);
    CHECK(wrong->status == 401);
    CHECK(wrong->get_header_value("Set-Cookie").empty());
    const auto right = page.Post("/login", {{"token", options.access_token}});
    REQUIRE(right);
    CHECK(right->status == 303);
    const std::string cookie = right->get_header_value("Set-Cookie");
    CHECK(cookie.find("haptel_console=" + options.access_token) == 0);
    CHECK(cookie.find("HttpOnly") != std::string::npos);
    CHECK(cookie.find("SameSite=Strict") != std::string::npos);

    const auto schedule =
        page.raw().Get("/", {{"Cookie", "other=1; haptel_console=" + options.access_token}});
    REQUIRE(schedule);
    CHECK(schedule->status == 200);
    CHECK(schedule->body.find("1 of 2 trials done") != std::string::npos);
  }
}

TEST_CASE(
    "The console serves HTTPS with the certificate security init makes; its names are the hosts it "
    "answers to") {
  const auto dir = test::ScratchDir("console-https") / "sec";
  link::InitSecurity(dir, {}, 2, {"console.test", "127.0.0.1"});
  // Another certificate for the same folder is refused, as are names a certificate cannot hold.
  CHECK_THROWS_WITH(link::AddConsoleCertificate(dir, {"other.test"}, 2),
                    Catch::Contains("already holds"));
  CHECK_THROWS_WITH(link::InitSecurity(dir.parent_path() / "bad", {}, 2, {"two words"}),
                    Catch::Contains("console name 'two words'"));
  CHECK_FALSE(std::filesystem::exists(dir.parent_path() / "bad"));
  const ConsoleCertificate certificate = FindConsoleCertificate(dir);
  CHECK(certificate.names == std::vector<std::string>{"console.test", "127.0.0.1"});
  CHECK_THROWS_WITH(FindConsoleCertificate(dir / "missing"),
                    Catch::Contains("console.pem") && Catch::Contains("haptel security init"));

  Study study("console-https-study");
  ConsoleOptions options;
  options.port = 0;
  options.host = "0.0.0.0";
  options.tls_certificate = certificate.certificate;
  options.tls_key = certificate.key;
  options.names = certificate.names;
  options.access_token = "fedcba9876543210fedcba9876543210";
  StudyConsole console(study.config, study.plan, study.db, study.questionnaires, options);
  CHECK(console.url().rfind("https://", 0) == 0);

  httplib::SSLClient tls("127.0.0.1", console.port());
  tls.set_ca_cert_path((dir / "ca.pem").c_str());
  tls.enable_server_certificate_verification(true);
  tls.set_read_timeout(20, 0);
  const auto login = tls.Get("/login");  // verified against the folder's CA: ca.pem
  REQUIRE(login);
  CHECK(login->status == 200);
  const std::string token = test::FormToken(login->body);
  const auto in = tls.Post("/login", {{"Host", "console.test:" + std::to_string(console.port())}},
                           httplib::Params{{"token", options.access_token}, {"csrf", token}});
  REQUIRE(in);
  CHECK(in->status == 303);
  CHECK(in->get_header_value("Set-Cookie").find("; Secure") != std::string::npos);

  // Plain HTTP to the HTTPS port gets nothing.
  httplib::Client plain("127.0.0.1", console.port());
  plain.set_read_timeout(20, 0);
  CHECK_FALSE(plain.Get("/login"));
  CHECK(console.connection_counters().tls_failed >= 1);
}
