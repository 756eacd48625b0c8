// Hostile and broken requests to `unique3d serve`: each is answered 4xx or 5xx with a JSON message (or,
// for a request cut short, the connection is dropped), nothing reaches a file outside the jobs folder,
// and the server goes on serving: after them all, a valid job completes.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <zip.h>
#include <zlib.h>

#include <atomic>

#include "server/zip_archive.h"
#include "server_fixture.h"

namespace u3d::server::test {
namespace {

std::string be32(uint32_t v) { return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }

std::string png_chunk(const std::string& type, const std::string& data) {
  const std::string body = type + data;
  const uLong crc = crc32(0, reinterpret_cast<const Bytef*>(body.data()), uInt(body.size()));
  return be32(uint32_t(data.size())) + body + be32(uint32_t(crc));
}

// A gray 8-bit PNG of `width` x `height` zero pixels, deflated: a few bytes per million pixels.
std::string zero_png(uint32_t width, uint32_t height, bool with_data = true) {
  std::string png = "\x89PNG\r\n\x1a\n";
  png += png_chunk("IHDR", be32(width) + be32(height) + std::string("\x08\x00\x00\x00\x00", 5));
  if (with_data) {
    const std::string raw(size_t(width + 1) * height, '\0');  // filter byte 0 and the row
    uLongf size = compressBound(uLong(raw.size()));
    std::string packed(size, '\0');
    compress2(reinterpret_cast<Bytef*>(packed.data()), &size, reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()), 9);
    packed.resize(size);
    png += png_chunk("IDAT", packed);
  }
  return png + png_chunk("IEND", "");
}

// A zip made with libzip itself, so that it can hold what ours refuses: a ".." name, a symbolic link.
std::string raw_zip(const std::vector<std::tuple<std::string, std::string, bool>>& entries) {
  const fs::path path = fs::temp_directory_path() / ("u3d_hostile_" + std::to_string(::getpid()) + ".zip");
  int error = 0;
  zip_t* z = zip_open(path.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &error);
  for (const auto& [name, data, link] : entries) {
    zip_source_t* s = zip_source_buffer(z, data.data(), data.size(), 0);
    const zip_int64_t i = zip_file_add(z, name.c_str(), s, 0);
    if (link) zip_file_set_external_attributes(z, zip_uint64_t(i), 0, ZIP_OPSYS_UNIX, (S_IFLNK | 0777u) << 16);
  }
  zip_close(z);
  std::string bytes = read_file(path);
  fs::remove(path);
  return bytes;
}

// Sends raw bytes on a new connection and returns what comes back before the server closes it (or
// `seconds` pass). With `hang_up`, the client's side is closed after sending (a body cut short); else it
// stays open as if more were coming.
std::string raw_request(int port, const std::string& bytes, int seconds = 10, bool hang_up = true) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(uint16_t(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    close(fd);
    return "";
  }
  timeval tv{seconds, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  (void)!send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
  if (hang_up) shutdown(fd, SHUT_WR);
  std::string reply;
  char buffer[4096];
  for (ssize_t n; (n = recv(fd, buffer, sizeof buffer, 0)) > 0;) {
    reply.append(buffer, size_t(n));
    const size_t head = reply.find("\r\n\r\n");
    const size_t length_at = reply.find("Content-Length: ");
    if (!hang_up && head != std::string::npos && length_at != std::string::npos &&
        reply.size() >= head + 4 + std::stoul(reply.substr(length_at + 16)))
      break;  // the whole reply is in
  }
  close(fd);
  return reply;
}

int reply_status(const std::string& reply) {
  return reply.rfind("HTTP/1.1 ", 0) == 0 ? std::atoi(reply.c_str() + 9) : 0;
}

httplib::MultipartFormDataItems views_with(const std::string& name, const std::string& data) {
  httplib::MultipartFormDataItems items = example_upload();
  for (auto& item : items)
    if (item.filename == name) item.content = data;
  return items;
}

struct Case {
  std::string what;
  std::function<std::pair<int, std::string>(ServerFixture&)> send;  // status, body
  int expected;
};

std::pair<int, std::string> post(ServerFixture& s, const httplib::MultipartFormDataItems& items) {
  auto res = s.client().Post("/api/jobs", items);
  return res ? std::make_pair(res->status, res->body) : std::make_pair(0, std::string());
}

std::pair<int, std::string> get(ServerFixture& s, const std::string& path, const httplib::Headers& headers = {}) {
  auto res = s.client().Get(path, headers);
  return res ? std::make_pair(res->status, res->body) : std::make_pair(0, std::string());
}

TEST(ServerHostile, EveryBadRequestIsAnsweredAndTheServerGoesOnServing) {
  ServerFixture server;
  const std::string png = read_file(example_views() / "front_rgb.png");
  const std::string unknown = "/api/jobs/0123456789abcdef0123456789abcdef";
  std::vector<Case> cases = {
      {"JSON instead of a form", [](auto& s) { auto r = s.client().Post("/api/jobs", "{\"views\": []}", "application/json"); return std::make_pair(r->status, r->body); }, 415},
      {"a form with no files", [](auto& s) { return post(s, {{"faces", "1000", "", ""}}); }, 400},
      {"not an image", [](auto& s) { return post(s, views_with("front_rgb.png", "just some text, not a PNG")); }, 400},
      {"a truncated PNG", [&](auto& s) { return post(s, views_with("front_rgb.png", png.substr(0, png.size() / 2))); }, 400},
      {"a PNG claiming 100k x 100k pixels", [](auto& s) { return post(s, views_with("front_rgb.png", zero_png(100000, 100000, false))); }, 400},
      {"a decompression-bomb PNG (6000^2 zeros in a few KB)", [](auto& s) { return post(s, views_with("front_normal.png", zero_png(6000, 6000))); }, 400},
      {"a zip with a ../ name", [&](auto& s) { return post(s, {{"views", raw_zip({{"../front_rgb.png", png, false}}), "v.zip", "application/zip"}}); }, 400},
      {"a zip with an absolute name", [&](auto& s) { return post(s, {{"views", raw_zip({{"/etc/front_rgb.png", png, false}}), "v.zip", "application/zip"}}); }, 400},
      {"a zip with a symbolic link", [&](auto& s) { return post(s, {{"views", raw_zip({{"front_rgb.png", "/etc/passwd", true}}), "v.zip", "application/zip"}}); }, 400},
      {"a file named .zip that is not one", [](auto& s) { return post(s, {{"views", "PK\x03\x04 not really", "v.zip", "application/zip"}}); }, 400},
      {"a view set lacking a file", [](auto& s) { auto items = example_upload(); items.pop_back(); return post(s, items); }, 400},
      {"a view file twice", [](auto& s) { auto items = example_upload(); items.push_back(items[0]); return post(s, items); }, 400},
      {"a file that is no view", [&](auto& s) { auto items = example_upload(); items.push_back({"views", png, "cat.png", "image/png"}); return post(s, items); }, 400},
      {"views of different sizes", [](auto& s) { return post(s, views_with("right_rgb.png", zero_png(64, 64))); }, 400},
      {"an unknown option", [](auto& s) { return post(s, example_upload({{"poisson", "9"}})); }, 400},
      {"faces not a number", [](auto& s) { return post(s, example_upload({{"faces", "many"}})); }, 400},
      {"faces negative", [](auto& s) { return post(s, example_upload({{"faces", "-5"}})); }, 400},
      {"a colour that is none", [](auto& s) { return post(s, example_upload({{"colour", "red"}})); }, 400},
      {"a texture size with vertex colours", [](auto& s) { return post(s, example_upload({{"colour", "vertex"}, {"texture_size", "1024"}})); }, 400},
      {"an option twice", [](auto& s) { return post(s, example_upload({{"faces", "1000"}, {"faces", "2000"}})); }, 400},
      {"an unexpected file field", [&](auto& s) { auto items = example_upload(); items.push_back({"mask", png, "m.png", "image/png"}); return post(s, items); }, 400},
      {"views and a photo at once", [&](auto& s) { auto items = example_upload(); items.push_back({"image", png, "p.png", "image/png"}); return post(s, items); }, 400},
      {"a kind that does not match", [](auto& s) { return post(s, example_upload({{"kind", "generate"}})); }, 400},
      {"a photo without a model folder", [&](auto& s) { return post(s, {{"image", png, "p.png", "image/png"}}); }, 409},
      {"a 2 GiB Content-Length", [](auto& s) {
         const std::string r = raw_request(s.port(), "POST /api/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: multipart/form-data; boundary=x\r\nContent-Length: 2147483648\r\n\r\n", 10, false);
         const size_t body = r.find("\r\n\r\n");
         return std::make_pair(reply_status(r), body == std::string::npos ? r : r.substr(body + 4)); }, 413},
      {"multipart without a boundary", [](auto& s) { auto r = s.client().Post("/api/jobs", "--x\r\n", "multipart/form-data"); return std::make_pair(r->status, r->body); }, 400},
      {"an unknown job", [&](auto& s) { return get(s, unknown); }, 404},
      {"an unknown job's events", [&](auto& s) { return get(s, unknown + "/events"); }, 404},
      {"cancelling an unknown job", [&](auto& s) { auto r = s.client().Post(unknown + "/cancel"); return std::make_pair(r->status, r->body); }, 404},
      {"a malformed job id", [](auto& s) { return get(s, "/api/jobs/XYZ"); }, 404},
      {".. in a path", [](auto& s) { return get(s, "/api/jobs/../../../etc/passwd"); }, 404},
      {"%2e%2e in a path", [](auto& s) { return get(s, "/%2e%2e/%2e%2e/etc/passwd"); }, 404},
      {"%2f in a file name", [&](auto& s) { return get(s, unknown + "/files/..%2f..%2finput%2ffront_rgb.png"); }, 404},
      {"another site's Host", [](auto& s) { return get(s, "/api/info", {{"Host", "evil.example:80"}}); }, 403},
      {"a post from another site's page", [](auto& s) {
         auto r = s.client().Post("/api/jobs", httplib::Headers{{"Origin", "http://evil.example"}}, example_upload()); return std::make_pair(r->status, r->body); }, 403},
      {"an unknown API path", [](auto& s) { return get(s, "/api/nothing"); }, 404},
      {"a method the API has not", [](auto& s) { auto r = s.client().Delete("/api/jobs"); return std::make_pair(r->status, r->body); }, 404},
  };
  ASSERT_GE(cases.size(), 25u);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const auto [status, body] = c.send(server);
    EXPECT_EQ(status, c.expected) << body;
    const nlohmann::json j = nlohmann::json::parse(body, nullptr, false);
    EXPECT_TRUE(j.is_object() && j.contains("error") && !j["error"].get<std::string>().empty()) << body;
    // Messages name the client's files, never the server's folders.
    EXPECT_EQ(body.find(server.jobs_dir().string()), std::string::npos) << body;
    int info = 0;
    server.fetch("/api/info", &info);
    ASSERT_EQ(info, 200) << "the server stopped answering";
  }
  // No job was made, and nothing was left in the jobs folder by any of them.
  EXPECT_TRUE(fs::is_empty(server.jobs_dir()));

  // A body cut short: the connection is dropped without a job, and the server serves on.
  const std::string head = "POST /api/jobs HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: multipart/form-data; boundary=x\r\nContent-Length: 100000\r\n\r\n";
  const int cut = reply_status(raw_request(server.port(), head + "--x\r\nContent-Disposition: form-data; name=\"views\"; filename=\"front_rgb.png\"\r\n\r\n" + png.substr(0, 500), 10));
  EXPECT_TRUE(cut == 0 || (cut >= 400 && cut < 500)) << cut;
  EXPECT_TRUE(fs::is_empty(server.jobs_dir()));

  // A valid job still completes.
  const auto [code, reply] = server.submit(example_upload(fast_options()));
  ASSERT_EQ(code, 202) << reply.dump();
  EXPECT_EQ(server.wait(reply["id"])["state"], "done");
}

// Photos, with a model folder named (the jobs only wait to be cancelled): one claiming 20000^2 pixels
// and one too small for generate are refused before any job is made; a good one is taken.
TEST(ServerHostile, PhotosTooLargeOrTooSmallAreRefused) {
  ServerFixture server(run_until_cancelled, 8, "/models-that-are-never-read");
  const auto too_large = post(server, {{"image", zero_png(20000, 20000, false), "p.png", "image/png"}});
  EXPECT_EQ(too_large.first, 400) << too_large.second;
  EXPECT_NE(too_large.second.find("larger than 8192"), std::string::npos) << too_large.second;
  const auto too_small = post(server, {{"image", zero_png(32, 32), "p.png", "image/png"}});
  EXPECT_EQ(too_small.first, 400) << too_small.second;
  const auto not_image = post(server, {{"image", "GIF89a....", "p.gif", "image/gif"}});
  EXPECT_EQ(not_image.first, 400) << not_image.second;
  EXPECT_TRUE(fs::is_empty(server.jobs_dir()));
  const auto good = post(server, {{"image", zero_png(256, 256), "p.png", "image/png"}, {"seed", "7", "", ""}});
  ASSERT_EQ(good.first, 202) << good.second;
  const nlohmann::json job = nlohmann::json::parse(good.second);
  EXPECT_EQ(job["kind"], "generate");
  EXPECT_EQ(job["options"]["seed"], 7);
  EXPECT_TRUE(fs::exists(server.jobs_dir() / job["id"].get<std::string>() / "input" / "photo.png"));
  server.client().Post("/api/jobs/" + job["id"].get<std::string>() + "/cancel");
  EXPECT_EQ(server.wait(job["id"], 10)["state"], "cancelled");
}

// 50 submissions at once against a queue of 8 behind a job that runs until cancelled: 8 or 9 are
// accepted (the 9th only if the worker took the first before the queue filled), every other one is
// refused 503 with a message, and after cancelling them all the queue takes a job again.
TEST(ServerHostile, FiftyConcurrentSubmissionsAgainstAQueueOfEight) {
  ServerFixture server(run_until_cancelled, 8);
  std::atomic<int> accepted{0}, refused{0}, other{0};
  std::vector<std::string> ids;
  std::mutex ids_mutex;
  std::vector<std::thread> threads;
  for (int i = 0; i < 50; ++i)
    threads.emplace_back([&] {
      httplib::Client c("127.0.0.1", server.port());
      // The uploads are checked one at a time, so the last ones wait: for the answer, and to send their
      // bodies while earlier ones are read (httplib's default write timeout, 5 s, was too short on a
      // slower machine: "Write", the client giving up, not the server).
      c.set_read_timeout(120, 0);
      c.set_write_timeout(120, 0);
      auto res = c.Post("/api/jobs", example_upload());
      if (res && res->status == 202) {
        ++accepted;
        std::lock_guard lock(ids_mutex);
        ids.push_back(nlohmann::json::parse(res->body)["id"]);
      } else if (res && res->status == 503 && res->body.find("queue is full") != std::string::npos) {
        ++refused;
      } else {
        ++other;
        ADD_FAILURE() << "neither taken nor refused as full: " << (res ? std::to_string(res->status) + " " + res->body : httplib::to_string(res.error()));
      }
    });
  for (std::thread& t : threads) t.join();
  EXPECT_GE(accepted, 8);
  EXPECT_LE(accepted, 9);
  EXPECT_EQ(refused, 50 - accepted);
  EXPECT_EQ(other, 0);
  // Positions: one running, the others waiting in order 1..n.
  std::set<int> positions;
  for (const std::string& id : ids) positions.insert(server.status(id)["position"].get<int>());
  EXPECT_EQ(positions.size(), ids.size());
  for (const std::string& id : ids) server.client().Post("/api/jobs/" + id + "/cancel");
  for (const std::string& id : ids) EXPECT_EQ(server.wait(id, 10)["state"], "cancelled");
  const auto [code, reply] = server.submit(example_upload());
  EXPECT_EQ(code, 202) << reply.dump();
  server.client().Post("/api/jobs/" + reply["id"].get<std::string>() + "/cancel");
}

// A client that hangs up on the event stream mid-job does not disturb the job or the server.
TEST(ServerHostile, AClientLeavingTheEventStreamMidJob) {
  ServerFixture server;
  const auto [code, reply] = server.submit(example_upload(fast_options()));
  ASSERT_EQ(code, 202) << reply.dump();
  const std::string id = reply["id"];
  const std::vector<SseEvent> events = server.follow(id, [](const SseEvent& e) { return e.type == "step"; });
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().type, "step");
  EXPECT_EQ(server.wait(id)["state"], "done");
  int status = 0;
  server.fetch("/api/jobs/" + id + "/files/mesh.glb", &status);
  EXPECT_EQ(status, 200);
}

}  // namespace
}  // namespace u3d::server::test
