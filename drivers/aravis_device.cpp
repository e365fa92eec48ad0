#include "drivers/aravis_device.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>

namespace rsd::drivers::aravis {

namespace {

constexpr uint16_t kGvcpPort = 3956;
constexpr size_t kFakeSerialMax = 15;  // the bootstrap serial field, less its NUL

std::optional<in_addr> parse_ipv4(const std::string& s) {
  in_addr a{};
  if (inet_pton(AF_INET, s.c_str(), &a) != 1) return std::nullopt;
  return a;
}

}  // namespace

const FormatName* find_format(const std::string& name) {
  for (const auto& f : kFormats)
    if (name == f.config) return &f;
  return nullptr;
}

bool is_fake(const std::string& id) { return id.rfind("Fake_", 0) == 0; }

void check_camera_id(const std::string& id) {
  if (is_fake(id)) {
    const size_t n = id.size() - 5;
    if (n == 0 || n > kFakeSerialMax)
      throw std::invalid_argument("aravis: camera '" + id + "': a fake camera's serial has 1 to 15 characters");
    return;
  }
  const auto a = parse_ipv4(id);
  if (!a)
    throw std::invalid_argument("aravis: camera '" + id +
                                "': expected an IPv4 address or Fake_<serial> (rsd opens cameras by address: "
                                "finding them by name would broadcast a discovery)");
  const uint32_t host = ntohl(a->s_addr);
  if (host == INADDR_BROADCAST || IN_MULTICAST(host) || host == INADDR_ANY)
    throw std::invalid_argument("aravis: camera '" + id + "' is not the address of one camera");
}

namespace {

// The local address the kernel sends from to reach `ip`. Connecting a UDP socket sends
// nothing; it only picks the route.
std::string route_source(const std::string& ip) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw CameraError("aravis: no UDP socket to reach " + ip + ": " + std::strerror(errno));
  sockaddr_in dst{};
  dst.sin_family = AF_INET;
  dst.sin_port = htons(kGvcpPort);
  dst.sin_addr = *parse_ipv4(ip);
  sockaddr_in src{};
  socklen_t len = sizeof src;
  const bool ok = connect(fd, reinterpret_cast<sockaddr*>(&dst), sizeof dst) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&src), &len) == 0;
  const int err = errno;
  close(fd);
  if (!ok) throw CameraError("aravis: no route to a camera at " + ip + ": " + std::strerror(err));
  char buf[INET_ADDRSTRLEN];
  inet_ntop(AF_INET, &src.sin_addr, buf, sizeof buf);
  return buf;
}

GPtr<ArvDevice> open_gige(const std::string& ip) {
  const std::string local = route_source(ip);
  GPtr<GInetAddress> iface(g_inet_address_new_from_string(local.c_str()));
  GPtr<GInetAddress> device(g_inet_address_new_from_string(ip.c_str()));
  GErr err;
  ArvDevice* d = arv_gv_device_new(iface.get(), device.get(), err.out());
  if (d) return GPtr<ArvDevice>(d);
  if (err.transport())
    throw CameraError("no GigE Vision camera answered at " + ip + " (asked from " + local + "): " + err.message());
  throw CameraError("the GigE Vision camera at " + ip + " could not be opened: " + err.message());
}

GPtr<ArvDevice> open_fake(const std::string& id) {
  GErr err;
  ArvDevice* d = arv_fake_device_new(id.substr(5).c_str(), err.out());
  if (!d) throw CameraError("aravis: the fake camera " + id + " could not be made: " + err.message());
  return GPtr<ArvDevice>(d);
}

}  // namespace

GPtr<ArvDevice> open_device(const std::string& id) { return is_fake(id) ? open_fake(id) : open_gige(id); }

}  // namespace rsd::drivers::aravis
