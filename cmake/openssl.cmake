# OpenSSL 3 libcrypto (libssl-dev): SHA-256 digests of the batch layer's inputs and outputs.
include(require)
find_package(OpenSSL 3 QUIET COMPONENTS Crypto)
sd_require_target(OpenSSL::Crypto libssl-dev "OpenSSL 3 (libcrypto)")
