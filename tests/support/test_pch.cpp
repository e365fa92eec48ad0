// The object that carries the tests' precompiled header (tests/support/test_pch.hpp).
