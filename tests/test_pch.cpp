// The source of chlorovdb_test_pch, whose precompiled header every test binary reuses (tests/CMakeLists.txt).
