#include "bridge/link_auth.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>

#include "files/input_file.hpp"
#include "realtime/clock.hpp"

namespace tsmh::bridge {
namespace {

constexpr std::array<std::uint8_t, 4> kMagic = {'T', 'S', 'M', 'A'};
constexpr std::uint8_t kVersion = 2;
// The trailer bytes under the MAC (everything before it), per version.
constexpr std::size_t kSignedTrailerBytes = kAuthTrailerBytes - kAuthMacBytes;
constexpr std::size_t kSignedTrailerV1Bytes = kAuthTrailerV1Bytes - kAuthMacBytes;

std::size_t signed_bytes(std::size_t trailer_size) noexcept {
  return trailer_size == kAuthTrailerBytes ? kSignedTrailerBytes : kSignedTrailerV1Bytes;
}

void init_sodium() {
  // Idempotent and thread-safe; -1 only when no random source can be opened.
  if (sodium_init() < 0) throw LinkKeyError("libsodium could not be initialised");
}

void put_u64(std::uint8_t* p, std::uint64_t v) noexcept {
  for (int i = 0; i < 8; ++i)
    p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

std::uint64_t get_u64(const std::uint8_t* p) noexcept {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i)
    v = (v << 8) | p[i];
  return v;
}

void write_header(const AuthTrailer& t, std::uint8_t* out) noexcept {
  std::memcpy(out, kMagic.data(), kMagic.size());
  out[4] = kVersion;
  out[5] = out[6] = out[7] = 0;
  put_u64(out + 8, t.sender_id);
  put_u64(out + 16, t.seq);
  put_u64(out + 24, static_cast<std::uint64_t>(t.send_time_us));
  put_u64(out + 32, t.peer_id);
}

AuthTrailer read_header(const std::uint8_t* in) noexcept {
  AuthTrailer t{get_u64(in + 8), get_u64(in + 16), static_cast<std::int64_t>(get_u64(in + 24))};
  t.version = in[4];
  t.peer_id = t.version >= 2 ? get_u64(in + 32) : 0;
  return t;
}

// The MAC binds the channel (a MASTER_COMMAND cannot be replayed as another
// arm's), the payload and the trailer's identity, sequence, time and peer.
// The 0x00 separates channel from payload (channel names never contain it).
void compute_mac(const LinkKey& key, std::string_view channel, const std::uint8_t* payload,
                 std::size_t size, const std::uint8_t* header, std::size_t header_size,
                 std::uint8_t mac[kAuthMacBytes]) noexcept {
  crypto_auth_hmacsha512256_state st;
  crypto_auth_hmacsha512256_init(&st, key.bytes().data(), key.bytes().size());
  crypto_auth_hmacsha512256_update(&st, reinterpret_cast<const unsigned char*>(channel.data()),
                                   channel.size());
  const unsigned char zero = 0;
  crypto_auth_hmacsha512256_update(&st, &zero, 1);
  crypto_auth_hmacsha512256_update(&st, payload, size);
  crypto_auth_hmacsha512256_update(&st, header, header_size);
  crypto_auth_hmacsha512256_final(&st, mac);
  sodium_memzero(&st, sizeof st);
}

bool mac_matches(const LinkKey& key, std::string_view channel, const std::uint8_t* data,
                 std::size_t payload_size, std::size_t trailer_size) noexcept {
  const std::uint8_t* header = data + payload_size;
  const std::size_t signed_size = signed_bytes(trailer_size);
  std::uint8_t mac[kAuthMacBytes];
  compute_mac(key, channel, data, payload_size, header, signed_size, mac);
  // Constant time: a timing difference must not tell an attacker how many
  // leading bytes of a forged MAC were right.
  return sodium_memcmp(mac, header + signed_size, kAuthMacBytes) == 0;
}

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

LinkKey LinkKey::generate() {
  init_sodium();
  LinkKey k;
  randombytes_buf(k.bytes_.data(), k.bytes_.size());
  return k;
}

LinkKey LinkKey::from_hex(std::string_view text, std::string_view where) {
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  const std::string_view hex =
      first == std::string_view::npos ? std::string_view{} : text.substr(first, last - first + 1);
  if (hex.size() != 2 * kLinkKeyBytes)
    throw LinkKeyError(std::string(where) + ": a link key is " + std::to_string(2 * kLinkKeyBytes) +
                       " hex digits, found " + std::to_string(hex.size()) +
                       " characters (create one with `tsm-link keygen`)");
  LinkKey k;
  for (std::size_t i = 0; i < kLinkKeyBytes; ++i) {
    const int hi = hex_value(hex[2 * i]);
    const int lo = hex_value(hex[2 * i + 1]);
    if (hi < 0 || lo < 0)
      throw LinkKeyError(std::string(where) + ": character " +
                         std::to_string(2 * i + (hi < 0 ? 1 : 2)) +
                         " of the key is not a hex digit");
    k.bytes_[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  return k;
}

LinkKey LinkKey::load(const std::filesystem::path& file) {
  init_sodium();
  const std::string name = file.string();
  struct stat st {};
  if (stat(name.c_str(), &st) != 0)
    throw LinkKeyError("link key " + name + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw LinkKeyError("link key " + name + " is not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw LinkKeyError("link key " + name + " has mode " + mode +
                       ": anyone who can read it can command the robot; it must be readable by "
                       "its owner only (chmod 600 " +
                       name + ")");
  }
  // Bounded (a key is 65 bytes) and never blocking, even if the file was
  // replaced by a FIFO since the stat() above.
  std::string s;
  try {
    s = files::read_file(file, files::kMaxKeyBytes);
  } catch (const files::FileError& e) {
    throw LinkKeyError(std::string("link key ") + e.what());
  }
  LinkKey k = from_hex(s, "link key " + name);
  sodium_memzero(s.data(), s.size());
  return k;
}

LinkKey::~LinkKey() {
  sodium_memzero(bytes_.data(), bytes_.size());
}

void LinkKey::save(const std::filesystem::path& file, bool overwrite) const {
  const std::string name = file.string();
  if (file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec)
      throw LinkKeyError("cannot create " + file.parent_path().string() + ": " + ec.message());
  }
  if (overwrite)
    unlink(name.c_str());  // a new file gets the 0600 mode below, an old one keeps its own
  const int fd = open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    if (errno == EEXIST)
      throw LinkKeyError("link key " + name +
                         " already exists: every peer holding it would lose the link; use "
                         "--force to replace it");
    throw LinkKeyError("cannot create link key " + name + ": " + std::strerror(errno));
  }
  static constexpr char kDigits[] = "0123456789abcdef";
  std::array<char, 2 * kLinkKeyBytes + 1> hex{};
  for (std::size_t i = 0; i < kLinkKeyBytes; ++i) {
    hex[2 * i] = kDigits[bytes_[i] >> 4];
    hex[2 * i + 1] = kDigits[bytes_[i] & 15];
  }
  hex[2 * kLinkKeyBytes] = '\n';
  const ssize_t n = write(fd, hex.data(), hex.size());
  const int write_errno = errno;
  sodium_memzero(hex.data(), hex.size());
  const bool ok = n == static_cast<ssize_t>(hex.size()) && fsync(fd) == 0;
  close(fd);
  if (!ok) {
    unlink(name.c_str());
    throw LinkKeyError("cannot write link key " + name + ": " + std::strerror(write_errno));
  }
}

std::string LinkKey::fingerprint() const {
  init_sodium();
  // A keyed hash with a fixed label, not the key itself: safe to print.
  static constexpr unsigned char kLabel[] = "tsmh link key fingerprint";
  std::array<unsigned char, 8> h{};
  crypto_generichash(h.data(), h.size(), kLabel, sizeof kLabel - 1, bytes_.data(), bytes_.size());
  std::string out;
  static constexpr char kDigits[] = "0123456789abcdef";
  for (unsigned char b : h) {
    out += kDigits[b >> 4];
    out += kDigits[b & 15];
  }
  return out;
}

std::size_t auth_trailer_size(const std::uint8_t* data, std::size_t size) noexcept {
  auto is = [&](std::size_t bytes, std::uint8_t version) {
    if (size < bytes) return false;
    const std::uint8_t* t = data + size - bytes;
    return std::memcmp(t, kMagic.data(), kMagic.size()) == 0 && t[4] == version;
  };
  if (is(kAuthTrailerBytes, kVersion)) return kAuthTrailerBytes;
  if (is(kAuthTrailerV1Bytes, 1)) return kAuthTrailerV1Bytes;
  return 0;
}

bool has_auth_trailer(const std::uint8_t* data, std::size_t size) noexcept {
  return auth_trailer_size(data, size) != 0;
}

MessageSigner::MessageSigner(std::shared_ptr<const LinkKey> key) : key_(std::move(key)) {
  if (!key_) throw LinkKeyError("MessageSigner: no key");
  init_sodium();
  // Random per Sender: a restarted process starts a new sequence space
  // that receivers cannot confuse with the old one.
  randombytes_buf(&sender_id_, sizeof sender_id_);
}

void MessageSigner::sign(std::string_view channel, const std::uint8_t* payload, std::size_t size,
                         std::uint8_t* trailer) noexcept {
  sign_at(channel, payload, size, next_seq_.fetch_add(1, std::memory_order_relaxed),
          realtime::wall_clock_utime(), trailer);
}

void MessageSigner::sign_at(std::string_view channel, const std::uint8_t* payload, std::size_t size,
                            std::uint64_t seq, std::int64_t send_time_us,
                            std::uint8_t* trailer) const noexcept {
  AuthTrailer t{sender_id_, seq, send_time_us};
  t.peer_id = peer_id();
  sign_as(channel, payload, size, t, trailer);
}

void MessageSigner::sign_as(std::string_view channel, const std::uint8_t* payload, std::size_t size,
                            const AuthTrailer& t, std::uint8_t* trailer) const noexcept {
  write_header(t, trailer);
  compute_mac(*key_, channel, payload, size, trailer, kSignedTrailerBytes,
              trailer + kSignedTrailerBytes);
}

MessageVerifier::MessageVerifier(std::shared_ptr<const LinkKey> key, VerifierOptions options)
    : key_(std::move(key)), options_(options) {
  if (!key_) throw LinkKeyError("MessageVerifier: no key");
  init_sodium();
}

MessageVerifier::Window* MessageVerifier::find(std::uint64_t sender_id) noexcept {
  for (auto& w : windows_)
    if (w.used && w.sender_id == sender_id) return &w;
  return nullptr;
}

MessageVerifier::Window& MessageVerifier::claim(std::uint64_t sender_id) noexcept {
  Window* victim = &windows_[0];
  for (auto& w : windows_) {
    if (!w.used) {
      victim = &w;
      break;
    }
    if (w.last_used < victim->last_used) victim = &w;
  }
  *victim = Window{};
  victim->sender_id = sender_id;
  victim->used = true;
  return *victim;
}

AuthResult MessageVerifier::verify(std::string_view channel, const std::uint8_t* data,
                                   std::size_t size, std::int64_t now_realtime_us) noexcept {
  AuthResult r;
  const std::size_t trailer_size = auth_trailer_size(data, size);
  if (trailer_size == 0) return r;  // Missing
  r.payload_size = size - trailer_size;
  r.trailer = read_header(data + r.payload_size);
  if (!mac_matches(*key_, channel, data, r.payload_size, trailer_size)) {
    r.verdict = AuthVerdict::kBadMac;
    return r;
  }
  if (r.trailer.version == 1 && !options_.accept_version_1) {
    r.verdict = AuthVerdict::kVersion1;
    return r;
  }
  // Differences in doubles: a hostile (but correctly signed) time must not overflow.
  r.age_us = static_cast<std::int64_t>(static_cast<double>(now_realtime_us) -
                                       static_cast<double>(r.trailer.send_time_us));
  if (options_.check_freshness &&
      (r.age_us > options_.max_age_us || r.age_us < -options_.max_age_us)) {
    r.verdict = AuthVerdict::kStale;
    return r;
  }
  const std::uint64_t seq = r.trailer.seq;
  Window* w = find(r.trailer.sender_id);
  if (w != nullptr && seq <= w->top) {
    const bool too_old = w->top - seq >= kWindow;
    const std::uint64_t bit = std::uint64_t{1} << (seq % 64);
    if (too_old || (w->seen[(seq % kWindow) / 64] & bit) != 0) {
      r.verdict = AuthVerdict::kReplayed;
      return r;
    }
  }
  if (w == nullptr) {
    w = &claim(r.trailer.sender_id);
    w->top = seq;
  } else if (seq > w->top) {
    // Slide: forget the bits of the sequence numbers the window now covers anew.
    if (seq - w->top >= kWindow) {
      w->seen.fill(0);
    } else {
      for (std::uint64_t s = w->top + 1; s <= seq; ++s)
        w->seen[(s % kWindow) / 64] &= ~(std::uint64_t{1} << (s % 64));
    }
    w->top = seq;
  }
  w->seen[(seq % kWindow) / 64] |= std::uint64_t{1} << (seq % 64);
  w->last_used = ++uses_;
  r.verdict = AuthVerdict::kOk;
  return r;
}

AuthVerdict verify_stored(const LinkKey& key, std::string_view channel, const std::uint8_t* data,
                          std::size_t size) noexcept {
  const std::size_t trailer_size = auth_trailer_size(data, size);
  if (trailer_size == 0) return AuthVerdict::kMissing;
  return mac_matches(key, channel, data, size - trailer_size, trailer_size) ? AuthVerdict::kOk
                                                                            : AuthVerdict::kBadMac;
}

}  // namespace tsmh::bridge
