//! Cross-crate integration tests and the hard-case stress suite live in `tests/tests/`; this
//! library only holds helpers they share.
