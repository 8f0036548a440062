/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace pcl_movers {
namespace io {

/** \brief One UDP datagram of a packet capture: its payload and where it came from.
 */
struct UdpDatagram {
  double time = 0.0;  ///< capture time [s since the epoch] from the record header
  std::uint16_t source_port = 0;
  std::uint16_t destination_port = 0;
  std::uint32_t source_address = 0;  ///< IPv4, host order
  std::vector<std::uint8_t> payload;
};

/** \brief Reads the UDP datagrams of a libpcap capture file, one at a time.
 *
 * Follows the libpcap file format (tcpdump.org "pcap-savefile(5)", IETF draft
 * draft-ietf-opsawg-pcap): a 24-byte global header (magic 0xa1b2c3d4 for microsecond or
 * 0xa1b23c4d for nanosecond time stamps, in either byte order), then per packet a 16-byte record
 * header (seconds, fraction, captured length, original length) and the captured bytes. Link types
 * Ethernet (1, with or without one 802.1Q tag), raw IPv4 (101, 228) and Linux cooked capture (113)
 * are understood; datagrams are IPv4/UDP, unfragmented. Everything else (ARP, TCP, IPv6,
 * fragments) is skipped and counted. This is what `pcl::HDLGrabber` reads with libpcap, without
 * needing libpcap (and without its fixed 42-byte header assumption).
 *
 * Errors throw InputError naming the file: missing or unreadable file, not a pcap (bad magic),
 * unsupported link type. A capture cut inside its last record (a recorder killed mid-write) ends
 * there: isTruncated() tells.
 */
class PcapReader {
 public:
  /** \brief Opens the capture and reads its global header; throws InputError. */
  explicit PcapReader(const std::string& path);

  /** \brief The next UDP datagram; false at the end of the file. */
  bool next(UdpDatagram& datagram);

  const std::string& path() const { return path_; }
  /** \brief Link-layer header type of the global header (1 = Ethernet). */
  std::uint32_t linkType() const { return link_type_; }
  /** \brief Records read so far (all of them, UDP or not). */
  std::size_t recordCount() const { return records_; }
  /** \brief Records that were not an unfragmented IPv4/UDP datagram. */
  std::size_t skippedCount() const { return skipped_; }
  /** \brief True when the file ended inside a record. */
  bool isTruncated() const { return truncated_; }

 private:
  bool readRecord(double& time, std::vector<std::uint8_t>& bytes);
  bool parseDatagram(const std::vector<std::uint8_t>& bytes, UdpDatagram& datagram) const;

  std::string path_;
  std::ifstream in_;
  bool swapped_ = false;
  bool nanoseconds_ = false;
  std::uint32_t link_type_ = 0;
  std::size_t records_ = 0, skipped_ = 0;
  bool truncated_ = false;
  std::vector<std::uint8_t> record_;
};

/** \brief Writes UDP datagrams as a libpcap capture file, as `tcpdump -w` would have recorded them.
 *
 * Format: pcap-savefile(5), little endian, microsecond time stamps (magic 0xa1b2c3d4, version 2.4),
 * link type Ethernet (1). Each datagram becomes one record holding a broadcast Ethernet II header
 * (source MAC in Velodyne's OUI 60:76:88), an IPv4 header (RFC 791, 20 bytes, don't-fragment,
 * header checksum filled in) and a UDP header (RFC 768, checksum 0 = none, allowed over IPv4).
 * Files are written to `path + ".tmp"` and renamed into place by close(), so a failure leaves no
 * half-written capture; the destructor of an unclosed writer removes the temporary file.
 */
class PcapWriter {
 public:
  /** \brief Creates the capture; throws InputError naming the file when it cannot be written. */
  explicit PcapWriter(const std::string& path);
  ~PcapWriter();
  PcapWriter(const PcapWriter&) = delete;
  PcapWriter& operator=(const PcapWriter&) = delete;

  /** \brief Sets the source IPv4 address (host order; default 192.168.1.201, a Velodyne's). */
  void setSourceAddress(std::uint32_t address) { source_address_ = address; }
  /** \brief Appends one datagram sent at `time` [s since the epoch] between the given ports. */
  void write(double time, const std::uint8_t* payload, std::size_t size, std::uint16_t source_port,
             std::uint16_t destination_port);
  /** \brief Flushes and moves the file into place; throws InputError on a write error. */
  void close();
  std::size_t packetCount() const { return packets_; }

 private:
  std::string path_, tmp_path_;
  std::ofstream out_;
  std::uint32_t source_address_ = (192u << 24) | (168u << 16) | (1u << 8) | 201u;
  std::uint16_t ip_id_ = 0;
  std::size_t packets_ = 0;
  bool closed_ = false;
  std::vector<std::uint8_t> frame_;
};

}  // namespace io
}  // namespace pcl_movers
