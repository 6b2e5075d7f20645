#include "haptel/study/console.hpp"

#include <arpa/inet.h>
#include <httplib.h>
#include <openssl/pem.h>
#include <openssl/x509v3.h>
#include <sys/socket.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <sstream>
#include <thread>

#include "console_server.hpp"
#include "haptel/core/html.hpp"
#include "haptel/core/json.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/console_access.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/submission.hpp"

namespace haptel::study {
namespace {

std::string Html(const std::string& text) { return HtmlEscape(text); }

std::string Page(const std::string& title, const std::string& body,
                 const std::string& head_extra = "") {
  return "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" + Html(title) + "</title>" +
         head_extra +
         "<style>body{font-family:sans-serif;margin:2em;max-width:60em}table{border-collapse:"
         "collapse}"
         "td,th{border:1px solid #999;padding:0.2em "
         "0.6em}.done{background:#e6f4e6}.flagged{background:#fdf1d6}"
         ".flags{color:#a60}.error{color:#b00}"
         "fieldset{margin:0.8em 0}</style></head><body>\n" +
         body + "\n</body></html>\n";
}

std::string Query(const std::string& participant, const std::string& condition,
                  const std::string& name) {
  return "/questionnaire?participant=" + httplib::detail::encode_query_param(participant) +
         "&condition=" + httplib::detail::encode_query_param(condition) +
         "&name=" + httplib::detail::encode_query_param(name);
}

std::string FormatSeconds(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f s", s);
  return text;
}

std::string ErrorPage(const std::string& title, const std::string& why) {
  return Page(title, "<p id=\"result\" class=\"error\">" + Html(why) +
                         "</p><p><a href=\"/\">schedule</a></p>");
}

/// The hidden field every form carries (CheckFormToken).
std::string TokenField(const std::string& token) {
  return "<input type=\"hidden\" name=\"csrf\" value=\"" + Html(token) + "\">";
}

/// The small form that adds one of the experimenter's notes on a trial
/// (position 0: on the participant as a whole).
std::string NoteForm(const std::string& token, const std::string& participant, int position,
                     const std::string& id) {
  return "<form method=\"post\" action=\"/notes\" class=\"note\" accept-charset=\"utf-8\"" +
         (id.empty() ? std::string() : " id=\"" + Html(id) + "\"") + ">" + TokenField(token) +
         "<input type=\"hidden\" name=\"participant\" value=\"" + Html(participant) +
         "\"><input type=\"hidden\" name=\"position\" value=\"" + std::to_string(position) +
         "\"><input name=\"text\" size=\"24\" maxlength=\"" + std::to_string(kMaxNoteCharacters) +
         "\" placeholder=\"what you saw\" aria-label=\"note\"> <button>note</button></form>";
}

std::string LoginPage(const std::string& token, const std::string& why) {
  return Page(
      "Console: access token",
      "<h1>The study's console</h1>\n<p>" + Html(why) +
          "</p>\n<form method=\"post\" action=\"/login\">" + TokenField(token) +
          "<label>Access token <input name=\"token\" id=\"token\" size=\"34\" autocomplete=\"off\">"
          "</label> <button id=\"login\">Open</button></form>");
}

/// The largest url-encoded answers form of the study's questionnaires.
size_t LargestAnswers(const std::map<std::string, Questionnaire>& questionnaires) {
  size_t largest = 0;
  for (const auto& [name, q] : questionnaires) {
    size_t characters = 0;
    size_t fields = 4;  // participant, condition, questionnaire, csrf
    for (const Item& item : q.items) {
      if (item.type == ItemType::kText) characters += static_cast<size_t>(item.max_length);
      fields += 1 + item.tree.nodes.size();
    }
    largest = std::max(largest, FormBytesFor(characters, fields));
  }
  // Room for what a browser adds (field order, + for spaces), and a floor.
  return std::max<size_t>(largest + 4096, 16384);
}

/// The vehicle's latest camera picture, as it came (JPEG), handed over by
/// the session that runs the trial (SessionSetup::on_picture).
class Thumbnail {
 public:
  /// An empty picture keeps the last one: the page never counts frames it cannot show.
  void Set(std::vector<uint8_t> jpeg, uint64_t frames) {
    if (jpeg.empty()) return;
    const std::lock_guard<std::mutex> lock(mutex_);
    jpeg_ = std::move(jpeg);
    frames_ = frames;
  }
  std::vector<uint8_t> Latest() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return jpeg_;
  }
  uint64_t frames() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return frames_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<uint8_t> jpeg_;
  uint64_t frames_ = 0;
};

/// A tree item's yes/no fields ("<id>.node.<node>") turned into its path
/// ("<id>.path": node=yes,... from the first node to a band).
void TreePath(const Item& item, std::map<std::string, std::string>& fields) {
  std::string path;
  const TreeNode* node = item.tree.nodes.empty() ? nullptr : &item.tree.nodes.front();
  for (size_t guard = 0; node != nullptr && guard <= item.tree.nodes.size(); ++guard) {
    const auto answer = fields.find(item.id + ".node." + node->id);
    if (answer == fields.end() || (answer->second != "yes" && answer->second != "no")) break;
    path += (path.empty() ? "" : ",") + node->id + "=" + answer->second;
    node = item.tree.FindNode(answer->second == "yes" ? node->if_yes : node->if_no);
  }
  for (auto it = fields.begin(); it != fields.end();) {
    it = it->first.rfind(item.id + ".node.", 0) == 0 ? fields.erase(it) : std::next(it);
  }
  if (!path.empty()) fields[PathKey(item.id)] = path;
}

/// The decision tree walked one question at a time (Form's tree items): from
/// the first node, each answered question shows the node or band its answer
/// names; everything off that path is hidden and unchecked, so what is sent
/// is one path and a rating of the band it ends in.
constexpr const char* kTreeWalk = R"(<script>
document.querySelectorAll('div.tree').forEach(function (tree) {
  function step(id) { return document.getElementById(tree.dataset.item + '-step-' + id); }
  function walk() {
    var shown = [];
    var at = step(tree.dataset.first);
    while (at && shown.indexOf(at) < 0) {
      shown.push(at);
      if (!at.classList.contains('tree-node')) break;
      var answer = at.querySelector('input:checked');
      if (!answer) break;
      at = step(answer.value === 'yes' ? at.dataset.yes : at.dataset.no);
    }
    tree.querySelectorAll('.tree-node, .tree-band').forEach(function (e) {
      e.hidden = shown.indexOf(e) < 0;
      if (e.hidden) e.querySelectorAll('input').forEach(function (i) { i.checked = false; });
    });
  }
  tree.addEventListener('change', walk);
  walk();
});
</script>
)";

std::string Form(const Questionnaire& q, const std::string& participant,
                 const std::string& condition, const std::string& token) {
  std::ostringstream h;
  h << "<h1>" << Html(q.title) << "</h1>\n<p>Participant <b>" << Html(participant) << "</b>, "
    << (condition.empty() ? std::string("before their first trial")
                          : "after <b>" + Html(condition) + "</b>")
    << "</p>\n";
  if (!q.instructions.empty()) h << "<p>" << Html(q.instructions) << "</p>\n";
  h << "<form method=\"post\" action=\"/answers\" id=\"questionnaire\" accept-charset=\"utf-8\">"
    << TokenField(token) << "\n"
    << "<input type=\"hidden\" name=\"participant\" value=\"" << Html(participant) << "\">\n"
    << "<input type=\"hidden\" name=\"condition\" value=\"" << Html(condition) << "\">\n"
    << "<input type=\"hidden\" name=\"questionnaire\" value=\"" << Html(q.name) << "\">\n";
  for (const Item& item : q.items) {
    h << "<fieldset id=\"item-" << Html(item.id) << "\"><legend>" << Html(item.text)
      << (item.required ? "" : " (optional)") << "</legend>\n";
    switch (item.type) {
      case ItemType::kScale:
        if (!item.scale.min_label.empty()) h << Html(item.scale.min_label) << " ";
        for (int v = item.scale.min; v <= item.scale.max; v += item.scale.step) {
          h << "<label><input type=\"radio\" name=\"" << Html(item.id) << "\" value=\"" << v
            << "\">" << v << "</label> ";
        }
        if (!item.scale.max_label.empty()) h << Html(item.scale.max_label);
        break;
      case ItemType::kChoice:
        for (const ChoiceOption& o : item.options) {
          h << "<label><input type=\"radio\" name=\"" << Html(item.id) << "\" value=\""
            << Html(o.value) << "\">" << Html(o.label) << "</label><br>\n";
        }
        break;
      case ItemType::kText:
        h << "<textarea name=\"" << Html(item.id) << "\" rows=\"3\" cols=\"60\" maxlength=\""
          << item.max_length << "\"></textarea>";
        break;
      case ItemType::kTree: {
        // One question at a time, as the thesis's decision tree: the page's
        // script (kTreeWalk) shows the first question, then only the one the
        // answer leads to, and at the end the one band reached, whose
        // ratings are all the participant can pick. Changing an answer
        // clears everything after it. Without the script every question and
        // band shows, and the server still follows the answers (TreePath).
        const std::string id = Html(item.id);
        h << "<div class=\"tree\" data-item=\"" << id << "\" data-first=\""
          << Html(item.tree.nodes.empty() ? std::string() : item.tree.nodes.front().id) << "\">\n";
        for (const TreeNode& node : item.tree.nodes) {
          const std::string name = id + ".node." + Html(node.id);
          h << "<p class=\"tree-node\" id=\"" << id << "-step-" << Html(node.id) << "\" data-yes=\""
            << Html(node.if_yes) << "\" data-no=\"" << Html(node.if_no) << "\">"
            << Html(node.question) << " <label><input type=\"radio\" name=\"" << name
            << "\" value=\"yes\">yes</label> <label><input type=\"radio\" name=\"" << name
            << "\" value=\"no\">no</label></p>\n";
        }
        for (const TreeBand& band : item.tree.bands) {
          h << "<p class=\"tree-band\" id=\"" << id << "-step-" << Html(band.id) << "\"><b>"
            << Html(band.text) << "</b><br>\n";
          for (const BandRating& r : band.ratings) {
            h << "<label><input type=\"radio\" name=\"" << id << "\" value=\"" << r.rating << "\">"
              << r.rating << ": " << Html(r.text) << "</label><br>\n";
          }
          h << "</p>\n";
        }
        h << "</div>\n";
        break;
      }
    }
    h << "</fieldset>\n";
  }
  h << "<button type=\"submit\" id=\"submit\">Submit</button>\n</form>\n<p><a "
       "href=\"/\">schedule</a></p>"
    << kTreeWalk;
  return h.str();
}

}  // namespace

ConsoleCertificate FindConsoleCertificate(const std::filesystem::path& dir) {
  ConsoleCertificate found{dir / "console.pem", dir / "console.key", {}};
  const std::string make = "; make it with `haptel security init " + dir.string() +
                           " --console NAME,...` (NAME: "
                           "the address or host name the experimenter's browser uses)";
  for (const std::filesystem::path& file : {found.certificate, found.key}) {
    if (!std::filesystem::is_regular_file(file))
      throw ConsoleError("the console's HTTPS: no " + file.string() + make);
  }
  std::FILE* f = std::fopen(found.certificate.c_str(), "r");
  X509* cert = f != nullptr ? PEM_read_X509(f, nullptr, nullptr, nullptr) : nullptr;
  if (f != nullptr) std::fclose(f);
  if (cert == nullptr)
    throw ConsoleError("the console's HTTPS: " + found.certificate.string() +
                       " is not a PEM certificate" + make);
  const bool expired = X509_cmp_current_time(X509_get0_notAfter(cert)) < 0;
  const bool early = X509_cmp_current_time(X509_get0_notBefore(cert)) > 0;
  auto* names =
      static_cast<GENERAL_NAMES*>(X509_get_ext_d2i(cert, NID_subject_alt_name, nullptr, nullptr));
  for (int i = 0; names != nullptr && i < sk_GENERAL_NAME_num(names); ++i) {
    const GENERAL_NAME* name = sk_GENERAL_NAME_value(names, i);
    if (name->type == GEN_DNS) {
      const ASN1_STRING* dns = name->d.dNSName;
      found.names.emplace_back(reinterpret_cast<const char*>(ASN1_STRING_get0_data(dns)),
                               static_cast<size_t>(ASN1_STRING_length(dns)));
    } else if (name->type == GEN_IPADD) {
      const ASN1_OCTET_STRING* ip = name->d.iPAddress;
      char text[64] = {};
      const int family = ASN1_STRING_length(ip) == 4 ? AF_INET : AF_INET6;
      if (inet_ntop(family, ASN1_STRING_get0_data(ip), text, sizeof text) != nullptr)
        found.names.emplace_back(text);
    }
  }
  GENERAL_NAMES_free(names);
  X509_free(cert);
  if (expired || early) {
    throw ConsoleError("the console's HTTPS: " + found.certificate.string() +
                       (expired ? " has expired" : " is not valid yet") + make);
  }
  return found;
}

struct StudyConsole::Impl {
  StudyConfig config;
  std::vector<PlannedTrial> plan;  ///< written into the study's tables once the port is ours
  std::map<std::string, Questionnaire> questionnaires;
  ConsoleOptions options;
  record::Recorder recorder;
  std::unique_ptr<StudyStore> store;
  std::mutex mutex;  ///< the store and `live`: the server answers from several threads
  std::string live;
  /// The trial (or practice lap: position 0) under way, for its note form.
  std::string live_participant;
  int live_position = 0;
  LiveProgress progress;
  bool have_progress = false;
  /// An open study with nothing left to run waits for a participant or Finish.
  bool waiting_for_more = false;
  bool finish_requested = false;
  std::unique_ptr<Thumbnail> thumbnail;
  /// The trial the experimenter may start (empty: none waits), and whether
  /// they did; what the study waits for otherwise (questionnaires).
  std::string next;
  TrialDevice next_device;  ///< what the offered trial is driven with
  bool start_requested = false;
  std::string waiting;
  std::condition_variable started;
  std::atomic<bool> abort_requested{false};
  ConsoleAccess access;  ///< hosts filled in once the port is known
  std::unique_ptr<ConsoleServer> server;
  std::atomic<uint64_t> refused_requests{0};
  std::thread thread;
  int port = 0;

  Impl(const StudyConfig& c, const std::vector<PlannedTrial>& p,
       const std::filesystem::path& database, const std::map<std::string, Questionnaire>& q,
       const ConsoleOptions& o)
      : config(c), plan(p), questionnaires(q), options(o), recorder(database) {
    if (options.thumbnail) thumbnail = std::make_unique<Thumbnail>();
  }

  /// The page that says why a request was refused, and counts it.
  void Refuse(httplib::Response& res, const Refusal& refusal) {
    ++refused_requests;
    res.status = refusal.status;
    res.set_content(refusal.status == 401 ? LoginPage(access.form_token, refusal.reason)
                                          : ErrorPage("Refused", refusal.reason),
                    "text/html; charset=utf-8");
  }

  // The constructor's steps, in its order.
  void MakeServer();
  void SetAccess();
  void SetDefences();
  void AddRoutes();
  void Listen();

  // The routes (AddRoutes is their table).
  using Handler = void (Impl::*)(const httplib::Request&, httplib::Response&);
  using FormHandler = void (Impl::*)(const httplib::Request&, httplib::Response&,
                                     const httplib::ContentReader&);
  void Get(const std::string& path, Handler handler) {
    server->Get(path, [this, handler](const httplib::Request& req, httplib::Response& res) {
      (this->*handler)(req, res);
    });
  }
  /// A state-changing route: its form must carry the console's token.
  void Post(const std::string& path, Handler handler) {
    server->Post(path, [this, handler](const httplib::Request& req, httplib::Response& res) {
      if (const Refusal refusal = CheckFormToken(access, req.get_param_value("csrf")))
        return Refuse(res, refusal);
      (this->*handler)(req, res);
    });
  }
  /// A state-changing route whose form it reads itself (ReadForm: bounded as
  /// it is read, then its token checked).
  void PostForm(const std::string& path, FormHandler handler) {
    server->Post(path, [this, handler](const httplib::Request& req, httplib::Response& res,
                                       const httplib::ContentReader& read) {
      (this->*handler)(req, res, read);
    });
  }
  void LoginForm(const httplib::Request& req, httplib::Response& res);
  void Login(const httplib::Request& req, httplib::Response& res);
  void SchedulePage(const httplib::Request& req, httplib::Response& res);
  void Status(const httplib::Request& req, httplib::Response& res);
  void Start(const httplib::Request& req, httplib::Response& res);
  void Redo(const httplib::Request& req, httplib::Response& res);
  void AddParticipant(const httplib::Request& req, httplib::Response& res);
  void Finish(const httplib::Request& req, httplib::Response& res);
  void Picture(const httplib::Request& req, httplib::Response& res);
  void Abort(const httplib::Request& req, httplib::Response& res);
  void QuestionnaireForm(const httplib::Request& req, httplib::Response& res);
  void Answers(const httplib::Request& req, httplib::Response& res,
               const httplib::ContentReader& read);
  void Note(const httplib::Request& req, httplib::Response& res,
            const httplib::ContentReader& read);

  /// A url-encoded form read here, not by the library (which buffers one
  /// whole and refuses it past 8 kB, shorter than a long answer or note):
  /// refused as it is read past `limit`, then its form token checked. False
  /// (the refusal in `res`) when it is not to be handled.
  bool ReadForm(const httplib::Request& req, httplib::Response& res,
                const httplib::ContentReader& read, size_t limit, const std::string& allows,
                httplib::Params& params) {
    if (req.is_multipart_form_data() ||
        req.get_header_value("Content-Type").rfind("application/x-www-form-urlencoded", 0) != 0) {
      Refuse(res, {415, "refused: the form comes url-encoded"});
      return false;
    }
    std::string body;
    bool too_large = false;
    read([&](const char* data, size_t length) {
      too_large = body.size() + length > limit;
      if (!too_large) body.append(data, length);
      return !too_large;
    });
    if (too_large) {
      Refuse(res, {413, "refused: the form is larger than " + std::to_string(limit) +
                            " bytes, more than " + allows});
      return false;
    }
    httplib::detail::parse_query_text(body, params);
    const auto token = params.find("csrf");
    if (const Refusal refusal =
            CheckFormToken(access, token == params.end() ? "" : token->second)) {
      Refuse(res, refusal);
      return false;
    }
    return true;
  }

  /// The participants' count, and how many more complete a balanced block.
  std::string Blocks(size_t participants) const {
    const size_t block = static_cast<size_t>(BlockSize(config));
    std::string text =
        std::to_string(participants) + " participant" + (participants == 1 ? "" : "s");
    if (block > 1 && participants % block != 0) {
      const size_t more = block - participants % block;
      text += "; the balanced Latin square is balanced over blocks of " + std::to_string(block) +
              ": add " + std::to_string(more) + " more to complete the block";
    }
    return text;
  }

  /// The schedule page: the trial under way, what is next, every planned
  /// trial with its results, questionnaires and notes, and the forms.
  std::string Schedule() {
    const std::lock_guard<std::mutex> lock(mutex);
    const std::vector<PlannedTrial> plan = store->Plan();
    const std::vector<TrialRow> trials = store->Trials();
    const std::vector<NoteRow> notes = store->Notes();
    std::ostringstream h;
    h << "<h1>Study " << Html(config.name) << "</h1>\n<p id=\"progress\">" << trials.size()
      << " of " << plan.size() << " trials done</p>\n<p id=\"live\">"
      << (live.empty() ? "No trial under way." : Html(live)) << "</p>\n";
    if (!live.empty()) LiveTrial(h);
    if (!waiting.empty()) h << "<p id=\"waiting\">Waiting for " << Html(waiting) << "</p>\n";
    std::string missing;
    if (!next.empty()) {
      h << "<form method=\"post\" action=\"/start\">" << TokenField(access.form_token)
        << "<p id=\"next\">Next: " << Html(next)
        << " <button id=\"start\">Start</button></p></form>\n";
      missing = NextDeviceMissing();
      NextDevice(h, missing);
    }
    h << "<table "
         "id=\"schedule\"><tr><th>participant</th><th>position</th><th>condition</th>"
         "<th>device</th><th>lap</th><th>questionnaires</th><th>notes</th></tr>\n";
    for (const PlannedTrial& t : plan) ScheduleRow(h, t, trials, notes);
    h << "</table>\n";
    ParticipantNotes(h, notes);
    if (config.operators == "person") {
      h << "<p id=\"participants\">" << Html(Blocks(store->Participants().size())) << "</p>\n"
        << "<form method=\"post\" action=\"/participants\">" << TokenField(access.form_token)
        << "<label>New participant <input name=\"id\" "
           "id=\"new-participant\" size=\"12\"></label> <button id=\"add\">Add</button></form>\n";
    }
    if (waiting_for_more) {
      h << "<form method=\"post\" action=\"/finish\">" << TokenField(access.form_token)
        << "<p id=\"more\">Every trial is done: add a participant, or "
           "<button id=\"finish\">Finish the study</button></p></form>\n";
    }
    // Refreshed while something changes by itself (a trial under way, answers
    // awaited from another screen); still otherwise, so that links hold.
    // A device not there yet: the page shows when it is plugged in.
    const bool changing = !live.empty() || !waiting.empty() || !missing.empty();
    return Page("Study " + config.name, h.str(),
                changing ? "<meta http-equiv=\"refresh\" content=\"2\">" : "");
  }

  /// What the offered trial's device lacks ("" when it is there, or there
  /// is none to check). The caller holds `mutex`.
  std::string NextDeviceMissing() const {
    return next_device.unavailable ? next_device.unavailable() : std::string();
  }

  /// The offered trial's device, and what is missing while it is not there.
  /// The caller holds `mutex`.
  void NextDevice(std::ostringstream& h, const std::string& missing) const {
    if (next_device.name.empty()) return;
    h << "<p id=\"next-device\">Device: <b>" << Html(next_device.name) << "</b> ("
      << Html(next_device.file.string()) << ")</p>\n";
    if (!missing.empty()) {
      h << "<p id=\"device-missing\" class=\"error\">The device " << Html(next_device.name)
        << " is not there: " << Html(missing) << ". The trial cannot start until it is.</p>\n";
    }
  }

  /// The trial under way: its progress, the thumbnail, Abort, and its note
  /// form. The caller holds `mutex`.
  void LiveTrial(std::ostringstream& h) const {
    if (have_progress) {
      h << "<p id=\"progress-live\">lap " << FormatSeconds(progress.lap_time_s)
        << " &middot; gates " << progress.gates_passed << " of " << progress.gates_total
        << " &middot; contacts " << progress.obstacles;
      if (!progress.last_contact.empty()) h << " (last: " << Html(progress.last_contact) << ")";
      h << "</p>\n";
      if (!progress.message.empty())
        h << "<p id=\"screen-line\">their screen: " << Html(progress.message) << "</p>\n";
    }
    if (thumbnail) {
      h << "<p><img id=\"thumbnail\" src=\"/video.jpg?n=" << thumbnail->frames()
        << "\" width=\"320\" alt=\"the vehicle's camera (no picture yet)\"></p>\n";
    }
    h << "<form method=\"post\" action=\"/abort\">" << TokenField(access.form_token)
      << "<button id=\"abort\">Abort this trial</button> (it is "
         "run again)</form>\n";
    if (!live_participant.empty()) {
      h << "<p>Note on this " << (live_position == 0 ? "practice lap" : "trial") << ": "
        << NoteForm(access.form_token, live_participant, live_position, "live-note") << "</p>\n";
    }
  }

  /// One planned trial's row: its result and flags, redo, the questionnaires
  /// (the participant's background on their first row), notes. The caller
  /// holds `mutex`.
  void ScheduleRow(std::ostringstream& h, const PlannedTrial& t,
                   const std::vector<TrialRow>& trials, const std::vector<NoteRow>& notes) const {
    const TrialRow* row = nullptr;
    for (const TrialRow& r : trials) {
      if (r.participant == t.participant && r.position == t.position) row = &r;
    }
    const bool flagged = row != nullptr && !row->flags.empty();
    h << "<tr"
      << (row == nullptr ? ""
          : flagged      ? " class=\"done flagged\""
                         : " class=\"done\"")
      << "><td>" << Html(t.participant) << "</td><td>" << t.position << "</td><td>"
      << Html(t.condition) << "</td><td>" << Html(row != nullptr ? row->device : t.device)
      << "</td><td>"
      << (row == nullptr ? "" : FormatSeconds(row->lap_time_s) + (row->completed ? "" : " (cap)"));
    // What could have spoiled it: the experimenter decides whether to redo it.
    if (flagged) h << " <span class=\"flags\">! " << Html(row->flags) << "</span>";
    if (row != nullptr && row->attempt > 1) h << " (attempt " << row->attempt << ")";
    if (row != nullptr) {
      h << " <form method=\"post\" action=\"/redo\" style=\"display:inline\">"
        << TokenField(access.form_token)
        << "<input type=\"hidden\" "
           "name=\"participant\" value=\""
        << Html(t.participant) << "\"><input type=\"hidden\" name=\"position\" value=\""
        << t.position << "\"><button>redo</button></form>";
    }
    h << "</td><td>";
    // The participant's background, asked once before their first trial.
    if (!config.demographics.empty() && t.position == 1) {
      if (store->Answered(t.participant, "", config.demographics)) {
        h << Html(config.demographics) << " &#10003; ";
      } else {
        h << "<a class=\"demographics\" href=\""
          << Html(Query(t.participant, "", config.demographics)) << "\">"
          << Html(config.demographics) << "</a> (before the first trial) ";
      }
    }
    if (row != nullptr) {
      for (const std::string& name : config.questionnaires) {
        if (store->Answered(t.participant, t.condition, name)) {
          h << Html(name) << " &#10003; ";
        } else {
          h << "<a href=\"" << Html(Query(t.participant, t.condition, name)) << "\">" << Html(name)
            << "</a> ";
        }
      }
    }
    h << "</td><td>";
    for (const NoteRow& n : notes) {
      if (n.participant == t.participant && n.position == t.position) {
        h << "<div class=\"note-text\">" << Html(n.text) << "</div>";
      }
    }
    h << NoteForm(access.form_token, t.participant, t.position, "") << "</td></tr>\n";
  }

  /// Notes on a participant as a whole (their practice lap, their manner).
  static void ParticipantNotes(std::ostringstream& h, const std::vector<NoteRow>& notes) {
    bool general = false;
    for (const NoteRow& n : notes) {
      if (n.position != 0) continue;
      if (!general) h << "<h2>Notes on participants</h2>\n<ul id=\"participant-notes\">\n";
      general = true;
      h << "<li>" << Html(n.participant) << ": " << Html(n.text) << "</li>\n";
    }
    if (general) h << "</ul>\n";
  }
};

StudyConsole::StudyConsole(const StudyConfig& config, const std::vector<PlannedTrial>& plan,
                           const std::filesystem::path& database,
                           const std::map<std::string, Questionnaire>& questionnaires,
                           const ConsoleOptions& options)
    : impl_(std::make_unique<Impl>(config, plan, database, questionnaires, options)) {
  impl_->MakeServer();
  impl_->SetAccess();
  impl_->SetDefences();
  impl_->AddRoutes();
  impl_->Listen();
}

/// The server, over TLS when a certificate is given; refused beyond
/// loopback in clear unless `plain_http` accepts it.
void StudyConsole::Impl::MakeServer() {
  const bool tls = !options.tls_certificate.empty();
  if (!IsLoopbackAddress(options.host) && !tls && !options.plain_http) {
    throw ConsoleError(
        "the console would listen on " + options.host +
        ", beyond this machine, without HTTPS: its access token would cross the network in clear. "
        "Make a certificate with `haptel security init DIR --console NAME` and give --tls DIR, or "
        "accept plain HTTP on a network you trust with --plain-http");
  }
  TlsContext context;
  if (tls) {
    try {
      context = MakeTlsContext(options.tls_certificate, options.tls_key);
    } catch (const std::runtime_error& e) {
      throw ConsoleError(std::string("the console's HTTPS: ") + e.what());
    }
  }
  try {
    server = std::make_unique<ConsoleServer>(options.connections, std::move(context));
  } catch (const std::invalid_argument& e) {
    throw ConsoleError(e.what());
  }
}

/// The tokens (the forms', and beyond loopback the page's access token) and
/// the bounds on a form's body.
void StudyConsole::Impl::SetAccess() {
  access.tls = !options.tls_certificate.empty();
  access.form_token = RandomToken();
  access.access_token = !IsLoopbackAddress(options.host)
                            ? (options.access_token.empty() ? RandomToken() : options.access_token)
                            : "";
  access.max_answers_bytes = LargestAnswers(questionnaires);
  // A note's characters as 4 bytes of UTF-8 each, url-encoded, and room for
  // its hidden fields and what a browser adds.
  access.max_note_bytes = FormBytesFor(kMaxNoteCharacters, 4) + 4096;
  // Chunked bodies (no Content-Length) stop here as they are read.
  server->set_payload_max_length(std::max(access.max_answers_bytes, access.max_note_bytes));
}

/// What every answer carries, the checks every request's head passes
/// before its body is read or a route runs, and the pages of what the
/// library refuses by itself.
void StudyConsole::Impl::SetDefences() {
  // Not to be framed by another page (a hidden Abort button under a click),
  // sniffed as another type, cached, or named in a Referer to another site.
  // Not "no-referrer": under it Chromium sends the console's own form posts
  // with "Origin: null", which the Origin check must refuse.
  server->set_default_headers({{"X-Frame-Options", "DENY"},
                               {"Content-Security-Policy", "frame-ancestors 'none'"},
                               {"X-Content-Type-Options", "nosniff"},
                               {"Referrer-Policy", "same-origin"},
                               {"Cache-Control", "no-store"}});
  // Every request's head, before its body is read or a route runs.
  server->set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (const Refusal refusal = CheckRequest(access, req)) {
      Refuse(res, refusal);
      return httplib::Server::HandlerResponse::Handled;
    }
    return httplib::Server::HandlerResponse::Unhandled;
  });
  // What the library refuses by itself (a malformed request, a chunked body
  // past the limit, a path that is not a route) says so on a page too.
  server->set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (!res.body.empty()) return;  // a route's own page, which says why
    const std::string why =
        res.status == 404   ? "no such page on the study's console"
        : res.status == 413 ? "the form is larger than this console takes"
        : res.status == 400 ? "the request could not be read"
                            : "the request was refused (HTTP " + std::to_string(res.status) + ")";
    res.set_content(ErrorPage("Refused", why), "text/html; charset=utf-8");
  });
}

/// The console's routes, one a line. Every POST carries the form token:
/// Post checks it; PostForm's handlers read their forms themselves
/// (ReadForm), bounded, and check it there.
void StudyConsole::Impl::AddRoutes() {
  Get("/login", &Impl::LoginForm);
  Post("/login", &Impl::Login);
  Get("/", &Impl::SchedulePage);
  Get("/status.json", &Impl::Status);
  Post("/start", &Impl::Start);
  Post("/redo", &Impl::Redo);
  Post("/participants", &Impl::AddParticipant);
  Post("/finish", &Impl::Finish);
  Get("/video.jpg", &Impl::Picture);
  Post("/abort", &Impl::Abort);
  Get("/questionnaire", &Impl::QuestionnaireForm);
  PostForm("/answers", &Impl::Answers);
  PostForm("/notes", &Impl::Note);
}

/// Binds (refused when the port is taken), writes the study's tables, and
/// serves from a thread of its own.
void StudyConsole::Impl::Listen() {
  // SO_REUSEADDR only: httplib's default adds SO_REUSEPORT, with which a
  // second console would share the port silently instead of being refused.
  server->set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  if (options.port == 0) {
    port = server->bind_to_any_port(options.host);
  } else if (server->bind_to_port(options.host, options.port)) {
    port = options.port;
  }
  if (port <= 0) {
    throw ConsoleError("the console cannot listen on " + options.host + ":" +
                       std::to_string(options.port) +
                       " (the port is in use, or the address is not this machine's); choose "
                       "another with --port N");
  }
  access.hosts = ConsoleHosts(options.host, port, access.tls, options.names);
  // The study's tables only once the port is ours: a console that cannot
  // listen writes nothing.
  store = std::make_unique<StudyStore>(recorder, config, plan);
  thread = std::thread([this] { server->listen_after_bind(); });
  // Serving before the constructor returns: a stop() before the listening
  // loop has started would be lost, and the destructor would wait forever.
  for (int i = 0; i < 500 && !server->is_running(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

void StudyConsole::Impl::LoginForm(const httplib::Request&, httplib::Response& res) {
  res.set_content(LoginPage(access.form_token, "The console asks for its access token, once."),
                  "text/html; charset=utf-8");
}

void StudyConsole::Impl::Login(const httplib::Request& req, httplib::Response& res) {
  if (access.access_token.empty()) return res.set_redirect("/", 303);
  if (!IsAccessToken(access, req.get_param_value("token"))) {
    return Refuse(res, {401, "that is not the console's access token"});
  }
  res.set_header("Set-Cookie", std::string(kAccessCookie) + "=" + access.access_token +
                                   "; Path=/; HttpOnly; SameSite=Strict" +
                                   (access.tls ? "; Secure" : ""));
  res.set_redirect("/", 303);
}

void StudyConsole::Impl::SchedulePage(const httplib::Request&, httplib::Response& res) {
  res.set_content(Schedule(), "text/html; charset=utf-8");
}

void StudyConsole::Impl::Status(const httplib::Request&, httplib::Response& res) {
  const ConnectionCounters c = server->counters();
  const std::lock_guard<std::mutex> lock(mutex);
  res.set_content(
      "{\"study\":" + JsonString(config.name) +
          ",\"trials_done\":" + std::to_string(store->Trials().size()) +
          ",\"trials_planned\":" + std::to_string(store->Plan().size()) +
          ",\"participants\":" + std::to_string(store->Participants().size()) +
          ",\"live\":" + JsonString(live) + ",\"lap_time_s\":" + JsonNumber(progress.lap_time_s) +
          ",\"gates_passed\":" + std::to_string(progress.gates_passed) + ",\"obstacles\":" +
          std::to_string(progress.obstacles) + ",\"live_message\":" + JsonString(progress.message) +
          ",\"video_frames\":" + std::to_string(thumbnail ? thumbnail->frames() : 0) +
          ",\"next\":" + JsonString(next) +
          ",\"next_device\":" + JsonString(next.empty() ? std::string() : next_device.name) +
          ",\"device_missing\":" + JsonString(next.empty() ? std::string() : NextDeviceMissing()) +
          ",\"waiting\":" + JsonString(waiting) +
          ",\"waiting_for_participants\":" + (waiting_for_more ? "true" : "false") +
          ",\"connections\":{\"served\":" + std::to_string(c.served) + ",\"refused_busy\":" +
          std::to_string(c.refused_busy) + ",\"cut_deadline\":" + std::to_string(c.cut_deadline) +
          ",\"cut_for_room\":" + std::to_string(c.cut_for_room) + ",\"workers\":" +
          std::to_string(c.workers) + ",\"tls_failed\":" + std::to_string(c.tls_failed) +
          ",\"refused_requests\":" + std::to_string(refused_requests.load()) + "}}",
      "application/json");
}

void StudyConsole::Impl::Start(const httplib::Request&, httplib::Response& res) {
  std::unique_lock<std::mutex> lock(mutex);
  if (next.empty()) {
    res.status = 409;
    const std::string why =
        waiting.empty() ? "no trial is waiting to start" : "waiting for " + waiting;
    res.set_content(ErrorPage("Not started", why), "text/html; charset=utf-8");
    return;
  }
  // A trial whose device is not there would fail at its start, or run with
  // nobody able to drive it: refused, saying what is missing.
  if (const std::string missing = NextDeviceMissing(); !missing.empty()) {
    res.status = 409;
    res.set_content(ErrorPage("Not started",
                              "the trial is driven with the device " + next_device.name + " (" +
                                  next_device.file.string() + "), and it is not there: " + missing),
                    "text/html; charset=utf-8");
    return;
  }
  start_requested = true;
  started.notify_all();
  res.set_redirect("/", 303);
}

void StudyConsole::Impl::Redo(const httplib::Request& req, httplib::Response& res) {
  const std::string participant = req.get_param_value("participant");
  int position = 0;
  try {
    position = std::stoi(req.get_param_value("position"));
  } catch (const std::exception&) {
    position = 0;
  }
  bool taken = false;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    taken = position > 0 && store->Redo(participant, position, "from the console");
  }
  if (!taken) {
    res.status = 409;
    res.set_content(ErrorPage("Not redone", "participant " + participant +
                                                " has no finished trial at position " +
                                                req.get_param_value("position")),
                    "text/html; charset=utf-8");
    return;
  }
  res.set_redirect("/", 303);
}

void StudyConsole::Impl::AddParticipant(const httplib::Request& req, httplib::Response& res) {
  const std::string id = req.get_param_value("id");
  if (config.operators != "person") {
    res.status = 409;
    res.set_content(
        ErrorPage("Not added", "simulated drivers come from the study file, each with a profile"),
        "text/html; charset=utf-8");
    return;
  }
  if (!IsPlainName(id)) {
    res.status = 422;
    res.set_content(
        ErrorPage(
            "Not added",
            "a participant's id is 1 to 40 letters, digits, '-', '_' or '.', got '" + id + "'"),
        "text/html; charset=utf-8");
    return;
  }
  try {
    const std::lock_guard<std::mutex> lock(mutex);
    const int row = static_cast<int>(store->Participants().size());
    store->AddParticipant(id, PlanParticipant(config, id, row));
  } catch (const AlreadyAnswered& e) {
    res.status = 409;
    res.set_content(ErrorPage("Not added", e.what()), "text/html; charset=utf-8");
    return;
  }
  started.notify_all();
  res.set_redirect("/", 303);
}

void StudyConsole::Impl::Finish(const httplib::Request&, httplib::Response& res) {
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (!waiting_for_more) {
      res.status = 409;
      res.set_content(ErrorPage("Not finished", "the study still has trials to run"),
                      "text/html; charset=utf-8");
      return;
    }
    finish_requested = true;
  }
  started.notify_all();
  res.set_redirect("/", 303);
}

void StudyConsole::Impl::Picture(const httplib::Request&, httplib::Response& res) {
  const std::vector<uint8_t> jpeg = thumbnail ? thumbnail->Latest() : std::vector<uint8_t>();
  if (jpeg.empty()) {
    res.status = 404;
    res.set_content("no picture from the vehicle's camera yet", "text/plain");
    return;
  }
  res.set_content(std::string(jpeg.begin(), jpeg.end()), "image/jpeg");
}

void StudyConsole::Impl::Abort(const httplib::Request&, httplib::Response& res) {
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (live.empty()) {
      res.status = 409;
      res.set_content(ErrorPage("Not aborted", "no trial is under way"),
                      "text/html; charset=utf-8");
      return;
    }
  }
  abort_requested.store(true);
  res.set_redirect("/", 303);
}

void StudyConsole::Impl::QuestionnaireForm(const httplib::Request& req, httplib::Response& res) {
  const auto q = questionnaires.find(req.get_param_value("name"));
  if (q == questionnaires.end()) {
    res.status = 404;
    res.set_content(
        Page("Not found", "<p class=\"error\">No such questionnaire in this study.</p>"),
        "text/html; charset=utf-8");
    return;
  }
  res.set_content(Page(q->second.title, Form(q->second, req.get_param_value("participant"),
                                             req.get_param_value("condition"), access.form_token)),
                  "text/html; charset=utf-8");
}

// Read here, not by the library: it buffers a url-encoded body whole and
// refuses one past 8 kB, shorter than the answers a text item allows.
void StudyConsole::Impl::Answers(const httplib::Request& req, httplib::Response& res,
                                 const httplib::ContentReader& read) {
  httplib::Params params;
  if (!ReadForm(req, res, read, access.max_answers_bytes, "this study's questionnaires allow",
                params))
    return;
  std::map<std::string, std::string> fields;
  for (const auto& [key, value] : params) fields[key] = value;
  const std::string participant = fields["participant"];
  const std::string condition = fields["condition"];
  const std::string name = fields["questionnaire"];
  for (const char* hidden : {"participant", "condition", "questionnaire", "csrf"})
    fields.erase(hidden);
  const auto q = questionnaires.find(name);
  if (q != questionnaires.end()) {
    for (const Item& item : q->second.items) {
      if (item.type == ItemType::kTree) TreePath(item, fields);
    }
  }
  SubmissionResult result;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    result = SubmitAnswers(*store, questionnaires, participant, condition, name, fields,
                           config.demographics);
  }
  res.status = result.status;
  std::string page = std::string("<p id=\"result\" class=\"") + (result.accepted ? "ok" : "error") +
                     "\">" + Html(result.message) + "</p>\n";
  if (!result.errors.empty()) {
    page += "<ul id=\"errors\">\n";
    for (const AnswerError& e : result.errors) page += "<li>" + Html(e.message) + "</li>\n";
    page += "</ul>\n<p><a href=\"" + Html(Query(participant, condition, name)) +
            "\">back to the form</a></p>\n";
  }
  page += "<p><a href=\"/\">schedule</a></p>";
  res.set_content(Page(result.accepted ? "Recorded" : "Not recorded", page),
                  "text/html; charset=utf-8");
}

// One of the experimenter's notes on a trial; a long note (in any script)
// is larger than the library's own form limit, so read here.
void StudyConsole::Impl::Note(const httplib::Request& req, httplib::Response& res,
                              const httplib::ContentReader& read) {
  httplib::Params params;
  if (!ReadForm(req, res, read, access.max_note_bytes,
                "a note of " + std::to_string(kMaxNoteCharacters) + " characters takes", params)) {
    return;
  }
  const auto field = [&params](const char* key) {
    const auto it = params.find(key);
    return it == params.end() ? std::string() : it->second;
  };
  SubmissionResult result;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    result = SubmitNote(*store, field("participant"), field("position"), field("text"));
  }
  if (result.accepted) return res.set_redirect("/", 303);
  res.status = result.status;
  res.set_content(ErrorPage("Not noted", result.message), "text/html; charset=utf-8");
}

StudyConsole::~StudyConsole() {
  impl_->server->StopAll();
  if (impl_->thread.joinable()) impl_->thread.join();
}

int StudyConsole::port() const { return impl_->port; }

std::vector<std::string> StudyConsole::urls() const {
  return ConsoleUrls(impl_->options.host, impl_->port, impl_->access.tls, impl_->options.names);
}

std::string StudyConsole::url() const {
  const std::vector<std::string> all = urls();
  return all.empty() ? std::string() : all.front();
}

const std::string& StudyConsole::access_token() const { return impl_->access.access_token; }

bool StudyConsole::resumed() const { return impl_->store->resumed(); }

ConnectionCounters StudyConsole::connection_counters() const {
  ConnectionCounters c = impl_->server->counters();
  c.refused_requests = impl_->refused_requests.load();
  return c;
}

bool StudyConsole::TakeAbort() { return impl_->abort_requested.exchange(false); }

void StudyConsole::SetLive(const std::string& text, const std::string& participant, int position) {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->live = text;
  impl_->live_participant = text.empty() ? "" : participant;
  impl_->live_position = position;
  impl_->progress = {};
  impl_->have_progress = false;
}

void StudyConsole::SetLiveProgress(const LiveProgress& progress) {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->progress = progress;
  impl_->have_progress = true;
}

bool StudyConsole::WaitForMore(const std::atomic<bool>& stop) {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  impl_->waiting_for_more = true;
  impl_->finish_requested = false;
  bool more = false;
  while (!stop.load() && !impl_->finish_requested &&
         !(more = impl_->store->NextTrial().has_value())) {
    impl_->started.wait_for(lock, std::chrono::milliseconds(100));
  }
  impl_->waiting_for_more = false;
  return more;
}

void StudyConsole::SetPicture(std::vector<uint8_t> jpeg, uint64_t frames) {
  if (impl_->thumbnail) impl_->thumbnail->Set(std::move(jpeg), frames);
}

uint64_t StudyConsole::video_frames() const {
  return impl_->thumbnail ? impl_->thumbnail->frames() : 0;
}

void StudyConsole::SetWaiting(const std::string& text) {
  const std::lock_guard<std::mutex> lock(impl_->mutex);
  impl_->waiting = text;
}

bool StudyConsole::WaitForStart(const std::string& next, const std::atomic<bool>& stop,
                                const TrialDevice& device) {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  impl_->next = next;
  impl_->next_device = device;
  impl_->start_requested = false;
  // Polled as well: a signal sets `stop` without notifying.
  while (!impl_->start_requested && !stop.load()) {
    impl_->started.wait_for(lock, std::chrono::milliseconds(50));
  }
  impl_->next.clear();
  impl_->next_device = {};
  const bool start = impl_->start_requested;
  impl_->start_requested = false;
  impl_->abort_requested.store(false);
  return start;
}

const std::atomic<bool>& StudyConsole::abort_requested() const { return impl_->abort_requested; }

}  // namespace haptel::study
