#pragma once
// Content hashes of the files a run reads, so that a log can tell whether its inputs changed
// (RUN_INFO.file_sha256, issue 9). SHA-256 from OpenSSL's libcrypto (Debian's libssl-dev): a
// well-kept implementation rather than one written here; a 64-bit checksum would also detect an
// edit, but a standard digest can be checked with `sha256sum` by anyone.

#include <string>

namespace hapsim {

// SHA-256 of `bytes` as 64 lowercase hex digits.
std::string Sha256Hex(const std::string& bytes);

// SHA-256 of the content of the file at `path`. Throws InputError naming it if it cannot be read.
std::string Sha256OfFile(const std::string& path);

}  // namespace hapsim
