/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/common.h>
#include <pcl_movers/io/pcap_file.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace pcl_movers {
namespace io {

namespace {

constexpr std::uint32_t kMagicMicro = 0xa1b2c3d4u, kMagicNano = 0xa1b23c4du;
constexpr std::uint32_t kLinkEthernet = 1, kLinkRaw = 101, kLinkIpv4 = 228, kLinkLinuxSll = 113;
constexpr std::size_t kMaxRecord = 1u << 18;  // larger than any snapshot length in use

std::uint32_t swap32(std::uint32_t v) {
  return (v >> 24) | ((v >> 8) & 0xff00u) | ((v << 8) & 0xff0000u) | (v << 24);
}

std::uint16_t big16(const std::uint8_t* p) {
  return std::uint16_t((p[0] << 8) | p[1]);
}

std::uint32_t big32(const std::uint8_t* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         p[3];
}

void putLittle32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(std::uint8_t(v >> (8 * k)));
}

void putBig16(std::uint8_t* p, std::uint16_t v) {
  p[0] = std::uint8_t(v >> 8);
  p[1] = std::uint8_t(v);
}

void putBig32(std::uint8_t* p, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) p[k] = std::uint8_t(v >> (24 - 8 * k));
}

/** RFC 791 header checksum: one's complement of the one's complement sum of 16-bit words. */
std::uint16_t ipChecksum(const std::uint8_t* header, std::size_t size) {
  std::uint32_t sum = 0;
  for (std::size_t k = 0; k + 1 < size; k += 2) sum += big16(header + k);
  while (sum >> 16) sum = (sum & 0xffffu) + (sum >> 16);
  return std::uint16_t(~sum);
}

}  // namespace

PcapReader::PcapReader(const std::string& path) : path_(path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, 0, "does not exist");
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path, 0, "is a folder, not a .pcap capture");
  in_.open(path, std::ios::binary);
  if (!in_) throw InputError(path, 0, "cannot open");
  std::uint8_t header[24];
  if (!in_.read(reinterpret_cast<char*>(header), sizeof(header)))
    throw InputError(path, 0, "not a pcap capture (shorter than the 24-byte pcap header)");
  auto little32 = [&](int at) {
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = (v << 8) | header[at + k];
    return swapped_ ? swap32(v) : v;
  };
  const std::uint32_t magic = little32(0);
  if (magic == kMagicMicro || magic == kMagicNano) {
    swapped_ = false;
  } else if (swap32(magic) == kMagicMicro || swap32(magic) == kMagicNano) {
    swapped_ = true;
  } else {
    char hex[16];
    std::snprintf(hex, sizeof(hex), "0x%08x", unsigned(magic));
    throw InputError(path, 0,
                     std::string("not a pcap capture (magic number ") + hex +
                         ", expected 0xa1b2c3d4; pcapng files must be converted with "
                         "'editcap -F pcap')");
  }
  nanoseconds_ = (swapped_ ? swap32(magic) : magic) == kMagicNano;
  link_type_ = little32(20) & 0x0fffffffu;  // upper bits: FCS flags
  if (link_type_ != kLinkEthernet && link_type_ != kLinkRaw && link_type_ != kLinkIpv4 &&
      link_type_ != kLinkLinuxSll)
    throw InputError(path, 0,
                     "pcap link type " + std::to_string(link_type_) +
                         " is not supported (Ethernet, raw IPv4 or Linux cooked capture)");
}

bool PcapReader::readRecord(double& time, std::vector<std::uint8_t>& bytes) {
  std::uint8_t header[16];
  in_.read(reinterpret_cast<char*>(header), sizeof(header));
  if (in_.gcount() == 0) return false;
  if (in_.gcount() != std::streamsize(sizeof(header))) {
    truncated_ = true;
    return false;
  }
  auto field = [&](int at) {
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = (v << 8) | header[at + k];
    return swapped_ ? swap32(v) : v;
  };
  const std::uint32_t captured = field(8);
  if (captured > kMaxRecord) {
    // A length no capture tool writes: the rest of the file cannot be trusted.
    truncated_ = true;
    return false;
  }
  time = double(field(0)) + double(field(4)) * (nanoseconds_ ? 1e-9 : 1e-6);
  bytes.resize(captured);
  in_.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(captured));
  if (in_.gcount() != std::streamsize(captured)) {
    truncated_ = true;
    return false;
  }
  ++records_;
  return true;
}

bool PcapReader::parseDatagram(const std::vector<std::uint8_t>& bytes,
                               UdpDatagram& datagram) const {
  std::size_t at = 0;
  const std::size_t n = bytes.size();
  if (link_type_ == kLinkEthernet) {
    if (n < 14) return false;
    std::uint16_t ether_type = big16(&bytes[12]);
    at = 14;
    if (ether_type == 0x8100 && n >= 18) {  // one 802.1Q VLAN tag
      ether_type = big16(&bytes[16]);
      at = 18;
    }
    if (ether_type != 0x0800) return false;
  } else if (link_type_ == kLinkLinuxSll) {
    if (n < 16 || big16(&bytes[14]) != 0x0800) return false;
    at = 16;
  }
  if (n < at + 20 || (bytes[at] >> 4) != 4) return false;
  const std::size_t ihl = std::size_t(bytes[at] & 0x0f) * 4;
  const std::uint16_t total = big16(&bytes[at + 2]);
  const std::uint16_t fragment = big16(&bytes[at + 6]);
  if (ihl < 20 || bytes[at + 9] != 17 || (fragment & 0x3fff) != 0) return false;  // UDP, whole
  if (total < ihl + 8 || n < at + total) return false;
  datagram.source_address = big32(&bytes[at + 12]);
  const std::size_t udp = at + ihl;
  datagram.source_port = big16(&bytes[udp]);
  datagram.destination_port = big16(&bytes[udp + 2]);
  const std::uint16_t udp_length = big16(&bytes[udp + 4]);
  if (udp_length < 8 || udp + udp_length > at + total) return false;
  datagram.payload.assign(bytes.begin() + std::ptrdiff_t(udp + 8),
                          bytes.begin() + std::ptrdiff_t(udp + udp_length));
  return true;
}

bool PcapReader::next(UdpDatagram& datagram) {
  double time = 0.0;
  while (readRecord(time, record_)) {
    if (parseDatagram(record_, datagram)) {
      datagram.time = time;
      return true;
    }
    ++skipped_;
  }
  return false;
}

PcapWriter::PcapWriter(const std::string& path) : path_(path), tmp_path_(path + ".tmp") {
  out_.open(tmp_path_, std::ios::binary | std::ios::trunc);
  if (!out_) throw InputError(path, 0, "cannot write (cannot create " + tmp_path_ + ")");
  std::vector<std::uint8_t> header;
  putLittle32(header, kMagicMicro);
  header.insert(header.end(), {2, 0, 4, 0});  // version 2.4
  putLittle32(header, 0);                     // thiszone: UTC
  putLittle32(header, 0);                     // sigfigs
  putLittle32(header, 65535);                 // snaplen
  putLittle32(header, kLinkEthernet);
  out_.write(reinterpret_cast<const char*>(header.data()), std::streamsize(header.size()));
}

PcapWriter::~PcapWriter() {
  if (closed_) return;
  out_.close();
  std::error_code ec;
  std::filesystem::remove(tmp_path_, ec);
}

void PcapWriter::write(double time, const std::uint8_t* payload, std::size_t size,
                       std::uint16_t source_port, std::uint16_t destination_port) {
  if (closed_) throw InputError(path_, 0, "capture already closed");
  if (size > 65535 - 28) throw InputError(path_, 0, "UDP payload too large for one datagram");
  const std::size_t frame_size = 14 + 20 + 8 + size;
  frame_.assign(frame_size, 0);
  std::uint8_t* f = frame_.data();
  for (int k = 0; k < 6; ++k) f[k] = 0xff;  // broadcast, as Velodyne sensors send by default
  const std::uint8_t source_mac[6] = {0x60, 0x76, 0x88, 0x00, 0x00, 0x01};
  std::copy(source_mac, source_mac + 6, f + 6);
  putBig16(f + 12, 0x0800);
  std::uint8_t* ip = f + 14;
  ip[0] = 0x45;  // IPv4, 20-byte header
  putBig16(ip + 2, std::uint16_t(20 + 8 + size));
  putBig16(ip + 4, ip_id_++);
  putBig16(ip + 6, 0x4000);  // don't fragment
  ip[8] = 255;               // TTL
  ip[9] = 17;                // UDP
  putBig32(ip + 12, source_address_);
  putBig32(ip + 16, 0xffffffffu);
  putBig16(ip + 10, ipChecksum(ip, 20));
  std::uint8_t* udp = ip + 20;
  putBig16(udp, source_port);
  putBig16(udp + 2, destination_port);
  putBig16(udp + 4, std::uint16_t(8 + size));
  std::copy(payload, payload + size, udp + 8);

  double seconds = std::floor(time);
  std::uint32_t micro = std::uint32_t(std::lround((time - seconds) * 1e6));
  if (micro >= 1000000u) {
    micro -= 1000000u;
    seconds += 1.0;
  }
  std::vector<std::uint8_t> record;
  putLittle32(record, std::uint32_t(seconds));
  putLittle32(record, micro);
  putLittle32(record, std::uint32_t(frame_size));
  putLittle32(record, std::uint32_t(frame_size));
  out_.write(reinterpret_cast<const char*>(record.data()), std::streamsize(record.size()));
  out_.write(reinterpret_cast<const char*>(f), std::streamsize(frame_size));
  if (!out_) throw InputError(path_, 0, "cannot write (disk full?)");
  ++packets_;
}

void PcapWriter::close() {
  if (closed_) return;
  out_.flush();
  const bool good = bool(out_);
  out_.close();
  std::error_code ec;
  if (!good) {
    std::filesystem::remove(tmp_path_, ec);
    closed_ = true;
    throw InputError(path_, 0, "cannot write");
  }
  std::filesystem::rename(tmp_path_, path_, ec);
  closed_ = true;
  if (ec) {
    std::filesystem::remove(tmp_path_, ec);
    throw InputError(path_, 0, "cannot write (" + ec.message() + ")");
  }
}

}  // namespace io
}  // namespace pcl_movers
