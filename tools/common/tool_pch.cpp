// The object that carries the tools' precompiled header (tools/common/tool_pch.hpp).
