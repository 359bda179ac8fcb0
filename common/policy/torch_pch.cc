// The translation unit that builds modskill_torch_pch's precompiled torch header
// (common/CMakeLists.txt); it has no code of its own.
