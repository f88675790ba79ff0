-- xfgcu.lua: Wireshark dissector for XF Robot gimbal GCUs, "GCU private protocol" V2.0.6.
--
-- Shipped with the Python package gcu_async: `gcu-async wireshark --install` writes it to
-- Wireshark's personal Lua plugin folder; `tshark -X lua_script:$(gcu-async wireshark
-- --print-path)` loads it once.
--
-- What it dissects
--   * UDP ports 2337 (GCU) and 2338 (host), TCP port 2332 (GCU server), and, by heuristics
--     (a payload holding a whole packet: header, length, CRC), any other UDP or TCP port;
--     the bytes of each TCP direction are put in sequence order and reassembled here.
--   * Serial links captured by gcu_async (`capture=`, `--capture`): link type DLT_USER5
--     (LINKTYPE 152), one record per read or write, the pcapng packet flags giving the
--     direction; the chunks of each direction are reassembled here.
--   * Both directions (host packets A8 E5, GCU packets 8A 5E); several packets per segment or
--     datagram, packets split across TCP segments or serial chunks, junk between them.
--
-- The byte stream is parsed exactly as gcu_async's deframer does (the "reference parse"):
-- at each position a header with a length in [72, 256] whose bytes are all there and whose
-- CRC-16/XMODEM (sent high byte first) matches is a packet; otherwise one byte is junk. Spans
-- that fail the CRC are shown as packets with a CRC error (expert info) when no valid packet
-- starts inside them. Receive is liberal, as in gcu_async: a CRC-valid packet always
-- dissects; each value V2.0.6 does not expect (a version other than 1 or 2, a parameter out
-- of range or of the wrong length, a status a command never answers, extra status bytes)
-- is an "anomaly" field with expert info, worded exactly as `gcu-async decode` words it.
-- Every value is shown in engineering units with the same digits as `gcu-async decode`
-- prints, and raw.
--
-- Frames are decoded here by hand, an independent second decoder of the library's: their
-- offsets, scales, signs and checks are written in this file. Command parameters are decoded
-- by one generic decoder driven by COMMAND_ROWS (each opcode's parameters in wire order,
-- with struct code, scale, unit, range and how decode reads them), so that a command added
-- to the protocol package reaches Wireshark without an edit here. All tables (names, flag
-- bits, COMMAND_ROWS) are generated from gcu_async.protocol when the dissector is built:
-- this file, as shipped in the package, holds the marker line where they go, and
-- `gcu-async wireshark --install` / `--print-path` write the complete dissector
-- (gcu_async.wireshark.dissector_source()).
--
-- Written for Lua 5.2 to 5.4; tested with Wireshark 4.0 (Lua 5.2).

local xfgcu = Proto("xfgcu", "XF Robot GCU private protocol V2.0.6")
local xfgcu_serial = Proto("xfgcu_serial", "XF GCU serial link")

-- @@XFGCU_TABLES@@

local MIN_LEN, MAX_LEN = 72, 256
local HOST_HEADER, GCU_HEADER = 0xA8E5, 0x8A5E
local SERIAL_WTAP = wtap_encaps and wtap_encaps.USER5 or 50

---------------------------------------------------------------------------------------------
-- bit operations and CRC-16/XMODEM (poly 0x1021, init 0, not reflected, no final xor)
---------------------------------------------------------------------------------------------
local band, bxor
do
  local lib = rawget(_G, "bit32") or rawget(_G, "bit")
  if lib then
    band, bxor = lib.band, lib.bxor
  else -- Lua 5.3+ without a bit library: native operators (a syntax error in Lua 5.2)
    band = load("return function(a, b) return a & b end")()
    bxor = load("return function(a, b) return a ~ b end")()
  end
end

local CRC_TABLE = {}
for i = 0, 255 do
  local c = i * 256
  for _ = 1, 8 do
    if c >= 0x8000 then
      c = bxor((c * 2) % 0x10000, 0x1021)
    else
      c = (c * 2) % 0x10000
    end
  end
  CRC_TABLE[i] = c
end

-- CRC of the bytes s[first..last] (1-based, inclusive)
local function crc16(s, first, last)
  local crc = 0
  for i = first, last do
    crc = bxor((crc % 256) * 256, CRC_TABLE[bxor(math.floor(crc / 256), s:byte(i))])
  end
  return crc
end

---------------------------------------------------------------------------------------------
-- number formatting: Python's repr of a float (shortest round-trip digits), as decode prints
---------------------------------------------------------------------------------------------
local function pyfloat(v)
  if v ~= v then return "NaN" end
  if v == math.huge then return "Infinity" end
  if v == -math.huge then return "-Infinity" end
  if v == 0 then return "0.0" end
  local s
  for p = 1, 17 do
    s = string.format("%." .. (p - 1) .. "e", v)
    if tonumber(s) == v then break end
  end
  local sign, first, frac, exp = s:match("^(-?)(%d)%.?(%d*)e([-+]%d+)$")
  exp = tonumber(exp)
  local digits = (first .. frac):gsub("0+$", "")
  if digits == "" then digits = "0" end
  if exp < -4 or exp >= 16 then
    local mant = digits:sub(1, 1)
    if #digits > 1 then mant = mant .. "." .. digits:sub(2) end
    return string.format("%s%se%s%02d", sign, mant, exp < 0 and "-" or "+", math.abs(exp))
  end
  if exp < 0 then
    return sign .. "0." .. string.rep("0", -exp - 1) .. digits
  end
  if #digits <= exp + 1 then
    return sign .. digits .. string.rep("0", exp + 1 - #digits) .. ".0"
  end
  return sign .. digits:sub(1, exp + 1) .. "." .. digits:sub(exp + 2)
end

local function int_text(v)
  return string.format("%d", v)
end

-- Leap seconds: the UTC dates (year, month; the 1st, 00:00) from which GPS - UTC is
-- 1, 2, ... 18 s (IERS Bulletin C). A fact table, as in gcu_async.protocol.gpstime.
local LEAP_STARTS = {
  {1981, 7}, {1982, 7}, {1983, 7}, {1985, 7}, {1988, 1}, {1990, 1}, {1991, 1}, {1992, 7},
  {1993, 7}, {1994, 7}, {1996, 1}, {1997, 7}, {1999, 1}, {2006, 1}, {2009, 1}, {2012, 7},
  {2015, 7}, {2017, 1},
}

-- days from 1970-01-01 to y-m-d (proleptic Gregorian; H. Hinnant's days_from_civil)
local function days_from_civil(y, m, d)
  y = m <= 2 and y - 1 or y
  local era = math.floor(y / 400)
  local yoe = y - era * 400
  local mp = m > 2 and m - 3 or m + 9
  local doy = math.floor((153 * mp + 2) / 5) + d - 1
  local doe = yoe * 365 + math.floor(yoe / 4) - math.floor(yoe / 100) + doy
  return era * 146097 + doe - 719468
end

local GPS_EPOCH_DAYS = days_from_civil(1980, 1, 6)
local LEAP_MS = {} -- each start as milliseconds since the GPS epoch, UTC counted
for i, ym in ipairs(LEAP_STARTS) do
  LEAP_MS[i] = (days_from_civil(ym[1], ym[2], 1) - GPS_EPOCH_DAYS) * 86400000
end

local function leap_count(t_ms)
  local n = 0
  for i, start in ipairs(LEAP_MS) do
    if t_ms >= start then n = i end
  end
  return n
end

-- milliseconds since 1980-01-06 00:00 -> ISO 8601 as Python's datetime.isoformat() prints it
local function iso_from_ms(total)
  local secs = math.floor(total / 1000)
  local millis = total - secs * 1000
  local days = math.floor(secs / 86400)
  local sod = secs - days * 86400
  local z = days + GPS_EPOCH_DAYS + 719468 -- days since 0000-03-01
  local era = math.floor(z / 146097)
  local doe = z - era * 146097
  local yoe = math.floor((doe - math.floor(doe / 1460) + math.floor(doe / 36524)
    - math.floor(doe / 146096)) / 365)
  local doy = doe - (365 * yoe + math.floor(yoe / 4) - math.floor(yoe / 100))
  local mp = math.floor((5 * doy + 2) / 153)
  local d = doy - math.floor((153 * mp + 2) / 5) + 1
  local m = mp < 10 and mp + 3 or mp - 9
  local y = yoe + era * 400 + (m <= 2 and 1 or 0)
  local text = string.format("%04d-%02d-%02dT%02d:%02d:%02d", y, m, d, math.floor(sod / 3600),
    math.floor(sod / 60) % 60, sod % 60)
  if millis > 0 then text = text .. string.format(".%06d", millis * 1000) end
  return text .. "+00:00"
end

-- GNSS week + ms of week -> UTC, two ways: GPS time with the leap seconds taken off (what
-- the library sends and decode shows as gnss_time_utc), and the document's rule (counted
-- from 1980-01-06, leap seconds ignored: gnss_time_document_rule).
local function gnss_iso(week, ms)
  local gps = week * 604800000 + ms
  local first = leap_count(gps) -- near a boundary the offset of the UTC instant is right
  return iso_from_ms(gps - 1000 * leap_count(gps - 1000 * first)), iso_from_ms(gps)
end

local function opcode_name(op)
  return OPCODE_NAMES[op] or string.format("UNKNOWN_0x%02X", op)
end

local ACRONYMS = {ok = "OK", gnss = "GNSS", gcu = "GCU", osd = "OSD", mavlink = "MAVLink"}
local function humanize(name)
  local text = name:lower():gsub("_", " "):gsub("%a+", function(w) return ACRONYMS[w] end)
  return (text:gsub("^%l", string.upper))
end

---------------------------------------------------------------------------------------------
-- fields
---------------------------------------------------------------------------------------------
local F = {}
local function def(kind, abbr, label, ...)
  F[abbr] = ProtoField[kind]("xfgcu." .. abbr, label, ...)
  return F[abbr]
end

-- envelope
def("uint16", "header", "Header", base.HEX)
def("string", "direction", "Direction")
def("uint16", "length", "Length", base.DEC)
def("uint8", "version", "Version", base.DEC)
def("uint16", "crc", "CRC", base.HEX)
def("uint16", "crc.computed", "Computed CRC", base.HEX)
def("string", "crc.status", "CRC status")
def("bytes", "reserved", "Reserved")
def("bytes", "junk", "Junk")
def("string", "anomaly", "Anomaly")
def("bytes", "sub.data", "Sub frame data")

-- host main frame
def("int16", "host.main.control_raw", "Control value (raw)")
def("double", "host.main.control_as_angles_deg", "As an angle (deg)")
def("uint8", "host.main.flags_raw", "Flags", base.HEX)
def("uint8", "host.main.flags_reserved", "Reserved bits", base.HEX, nil, 0xFA)
def("bool", "host.main.control_valid", "Control values valid", 8, nil, 0x04)
def("bool", "host.main.ins_valid", "Aircraft INS data valid", 8, nil, 0x01)
for _, axis in ipairs({"roll", "pitch", "yaw"}) do
  def("double", "host.main.aircraft_attitude_deg." .. axis, "Aircraft " .. axis .. " (deg)")
end
def("int32", "host.main.aircraft_attitude_raw", "Raw (0.01 deg)")
for _, axis in ipairs({"north", "east", "up"}) do
  def("double", "host.main.acceleration_m_s2." .. axis, "Acceleration " .. axis .. " (m/s^2)")
  def("double", "host.main.velocity_m_s." .. axis, "Velocity " .. axis .. " (m/s)")
end
def("int16", "host.main.acceleration_raw", "Raw (0.01 m/s^2)")
def("int16", "host.main.velocity_raw", "Raw (0.01 m/s)")
def("uint8", "host.main.subframe_request", "GCU sub frame requested", base.HEX)

-- host sub frame 0x01
def("uint8", "host.sub.header", "Sub frame header", base.HEX)
def("double", "host.sub.latitude_deg", "Aircraft latitude (deg)")
def("double", "host.sub.longitude_deg", "Aircraft longitude (deg)")
def("double", "host.sub.altitude_m", "Aircraft altitude MSL (m)")
def("int32", "host.sub.latitude_raw", "Raw (1e-7 deg)")
def("int32", "host.sub.longitude_raw", "Raw (1e-7 deg)")
def("int32", "host.sub.altitude_raw", "Raw (mm)")
def("uint8", "host.sub.satellites", "Satellites")
def("int16", "host.sub.gnss_week", "GNSS week")
def("uint32", "host.sub.gnss_ms", "GNSS milliseconds of week")
def("string", "host.sub.gnss_time_utc", "GNSS time (UTC)")
def("string", "host.sub.gnss_time_document_rule", "GNSS time, the document's rule")
def("double", "host.sub.relative_altitude_m", "Relative altitude (m)")
def("int32", "host.sub.relative_altitude_raw", "Raw (mm)")

-- host command
def("uint8", "host.command.opcode", "Command", base.HEX)
def("string", "host.command.command", "Command name")
def("bytes", "host.command.params", "Parameters")
def("int32", "host.command.params_raw", "Raw")

-- each command parameter: xfgcu.host.command.<command>.<parameter>, from COMMAND_ROWS
local INT_FIELDS = {B = "uint8", b = "int8", H = "uint16", h = "int16", I = "uint32", i = "int32"}
local SIGNED = {b = true, h = true, i = true}

local function param_abbr(row, name)
  return "host.command." .. row.command:lower() .. "." .. name
end

local function param_label(name)
  return humanize((name:gsub("%.", " ")))
end

local function with_unit(label, unit)
  if unit and unit ~= "" then return label .. " (" .. unit .. ")" end
  return label
end

local function def_param(row, name, kind, unit, ...)
  local abbr = param_abbr(row, name)
  if not F[abbr] then def(kind, abbr, with_unit(param_label(name), unit), ...) end
end

for _, row in pairs(COMMAND_ROWS) do
  for _, p in ipairs(row.params) do
    if p.segments then
      for _, seg in ipairs(p.segments) do
        if seg.field then def_param(row, seg.field, "double", seg.unit) end
      end
    elseif p.switch then
      def_param(row, p.name, "bool")
    elseif p.kind == "enum" then
      def_param(row, p.name, "string")
    elseif p.kind == "mask" then
      def_param(row, p.name, "uint8", nil, base.HEX)
    elseif p.scale ~= 1 then
      def_param(row, p.name, "double", p.unit)
    else
      def_param(row, p.name, INT_FIELDS[p.fmt], p.unit)
    end
  end
end

-- GCU main frame
def("uint8", "gcu.main.mode_raw", "Mode", base.HEX)
def("string", "gcu.main.mode", "Mode name")
def("uint16", "gcu.main.pod_status_raw", "Pod status", base.HEX)
def("int16", "gcu.main.miss_distance", "Miss distance")
def("int16", "gcu.main.miss_distance_raw", "Raw")
for _, axis in ipairs({"x", "y", "z"}) do
  def("double", "gcu.main.relative_angles_deg." .. axis, "Relative angle " .. axis:upper() .. " (deg)")
  def("double", "gcu.main.angular_rates_deg_s." .. axis, "Angular rate " .. axis:upper() .. " (deg/s)")
end
def("int16", "gcu.main.relative_angles_raw", "Raw (0.01 deg)")
def("int16", "gcu.main.angular_rates_raw", "Raw (0.1 deg/s)")
for _, axis in ipairs({"roll", "pitch", "yaw"}) do
  def("double", "gcu.main.attitude_deg." .. axis, "Camera " .. axis .. " (deg)")
end
def("int32", "gcu.main.attitude_raw", "Raw (0.01 deg)")

-- GCU sub frame 0x01
def("uint8", "gcu.sub.header", "Sub frame header", base.HEX)
def("double", "gcu.sub.hardware_version", "Hardware version")
def("uint8", "gcu.sub.hardware_version_raw", "Raw (0.1)")
def("double", "gcu.sub.firmware_version", "Firmware version")
def("uint8", "gcu.sub.firmware_version_raw", "Raw (0.1)")
def("uint8", "gcu.sub.pod_code", "Pod model code")
def("string", "gcu.sub.pod_model", "Pod model")
def("string", "gcu.sub.pod_model_member", "PodModel member")
def("uint16", "gcu.sub.fault_raw", "Faults", base.HEX)
def("double", "gcu.sub.target_distance_m", "Target distance (m)")
def("int32", "gcu.sub.target_distance_raw", "Raw (0.1 m)")
def("double", "gcu.sub.target_position.latitude", "Target latitude (deg)")
def("double", "gcu.sub.target_position.longitude", "Target longitude (deg)")
def("double", "gcu.sub.target_position.altitude", "Target altitude (m)")
def("int32", "gcu.sub.target_position_raw", "Raw")
def("double", "gcu.sub.camera1_zoom", "Camera 1 zoom (x)")
def("uint16", "gcu.sub.camera1_zoom_raw", "Raw (0.1 x)")
def("double", "gcu.sub.camera2_zoom", "Camera 2 zoom (x)")
def("uint16", "gcu.sub.camera2_zoom_raw", "Raw (0.1 x)")
def("uint8", "gcu.sub.thermal_flags_raw", "Thermal flags", base.HEX)
def("uint16", "gcu.sub.camera_flags_raw", "Camera flags", base.HEX)
def("uint16", "gcu.sub.pip_mode", "Picture-in-picture mode", base.DEC, nil, PIP_MODE_MASK)
def("int8", "gcu.sub.time_zone", "Time zone (h)")

-- GCU feedback
def("uint8", "gcu.feedback.opcode", "Feedback to", base.HEX)
def("string", "gcu.feedback.command", "Command name")
def("uint8", "gcu.feedback.status_raw", "Execution status", base.HEX)
def("bytes", "gcu.feedback.extra_status", "Extra status bytes")
def("string", "gcu.feedback.status", "Result")
def("uint8", "gcu.feedback.failed_cameras", "Failed cameras", base.HEX)

-- flag bits, one boolean per bit the protocol defines
local function def_bits(prefix, bits, width)
  local list = {}
  for _, bit in ipairs(bits) do
    local abbr = prefix .. "." .. bit[2]:lower()
    def("bool", abbr, humanize(bit[2]), width, nil, bit[1])
    list[#list + 1] = {mask = bit[1], abbr = abbr, name = bit[2]}
  end
  return list
end
local POD_STATUS = def_bits("gcu.main.pod_status", POD_STATUS_BITS, 16)
local FAULTS = def_bits("gcu.sub.faults", FAULT_BITS, 16)
local THERMAL = def_bits("gcu.sub.thermal_flags", THERMAL_BITS, 8)
local CAMERA_FLAGS = def_bits("gcu.sub.camera_flags", CAMERA_FLAG_BITS, 16)
local CAMERAS = def_bits("cameras", CAMERA_MASK_BITS, 8)

local serial_f = {
  direction = ProtoField.string("xfgcu_serial.direction", "Direction"),
  chunk = ProtoField.uint32("xfgcu_serial.chunk", "Bytes in this record"),
  pending = ProtoField.uint32("xfgcu_serial.pending", "Bytes carried over from earlier records"),
}
xfgcu_serial.fields = {serial_f.direction, serial_f.chunk, serial_f.pending}

do
  local list = {}
  for _, f in pairs(F) do list[#list + 1] = f end
  xfgcu.fields = list
end

local E = {
  crc = ProtoExpert.new("xfgcu.crc.bad", "CRC mismatch", expert.group.CHECKSUM,
    expert.severity.ERROR),
  anomaly = ProtoExpert.new("xfgcu.anomaly.expert", "A value V2.0.6 does not expect",
    expert.group.PROTOCOL, expert.severity.WARN),
  junk = ProtoExpert.new("xfgcu.junk.expert", "Bytes that are not part of any packet",
    expert.group.PROTOCOL, expert.severity.WARN),
  truncated = ProtoExpert.new("xfgcu.truncated", "Truncated packet", expert.group.MALFORMED,
    expert.severity.WARN),
  reserved = ProtoExpert.new("xfgcu.reserved.nonzero", "Reserved bits or bytes are not zero",
    expert.group.PROTOCOL, expert.severity.NOTE),
  bug = ProtoExpert.new("xfgcu.internal", "Dissector error (please report)",
    expert.group.MALFORMED, expert.severity.ERROR),
}
xfgcu.experts = {E.crc, E.anomaly, E.junk, E.truncated, E.reserved, E.bug}

---------------------------------------------------------------------------------------------
-- the reference parse
---------------------------------------------------------------------------------------------
local function u16be(s, i) -- i: 1-based
  return s:byte(i) * 256 + s:byte(i + 1)
end

local function is_header_start(b)
  return b == 0xA8 or b == 0x8A
end

local function header_at(s, i)
  local a, b = s:byte(i, i + 1)
  return (a == 0xA8 and b == 0xE5) or (a == 0x8A and b == 0x5E)
end

-- Parse s (a Lua string). final: the input ends here (a datagram); otherwise a stream whose
-- further bytes may follow. Returns the valid packets {start (0-based), len}, and, for a
-- stream, the offset from which the bytes must wait for more (nil: none wait).
local function reference_parse(s, final)
  local n = #s
  local packets = {}
  local pos = 0
  while pos < n do
    local i = pos
    while i < n - 1 and not header_at(s, i + 1) do i = i + 1 end
    if i >= n - 1 then
      if not final and is_header_start(s:byte(n)) then return packets, n - 1 end
      break
    end
    if n - i < 4 then
      if not final then return packets, i end
      pos = i + 1
    else
      local len = s:byte(i + 3) + s:byte(i + 4) * 256
      if len < MIN_LEN or len > MAX_LEN then
        pos = i + 1
      elseif i + len > n then
        if not final then return packets, i end
        pos = i + 1
      elseif crc16(s, i + 1, i + len - 2) == u16be(s, i + len - 1) then
        packets[#packets + 1] = {start = i, len = len}
        pos = i + len
      else
        pos = i + 1
      end
    end
  end
  return packets, nil
end

-- The bytes [a, b) that the reference parse discarded: spans that failed only their CRC and
-- lie wholly inside are shown as packets with a CRC error, the rest as junk.
local function split_gap(s, a, b, out)
  local junk_from = a
  local p = a
  while p < b do
    local len = (p + 4 <= b and header_at(s, p + 1)) and (s:byte(p + 3) + s:byte(p + 4) * 256)
    if len and len >= MIN_LEN and len <= MAX_LEN and p + len <= b then
      if p > junk_from then out[#out + 1] = {kind = "junk", start = junk_from, len = p - junk_from} end
      out[#out + 1] = {kind = "bad", start = p, len = len}
      p = p + len
      junk_from = p
    else
      p = p + 1
    end
  end
  if b > junk_from then out[#out + 1] = {kind = "junk", start = junk_from, len = b - junk_from} end
end

-- Everything to show for s[0, stop): packets, CRC-failed spans and junk, in order.
local function items_of(s, final)
  local packets, pending = reference_parse(s, final)
  local stop = pending or #s
  local out = {}
  local pos = 0
  for _, pkt in ipairs(packets) do
    if pkt.start > pos then split_gap(s, pos, pkt.start, out) end
    out[#out + 1] = {kind = "packet", start = pkt.start, len = pkt.len}
    pos = pkt.start + pkt.len
  end
  if stop > pos then split_gap(s, pos, stop, out) end
  return out, pending
end

---------------------------------------------------------------------------------------------
-- value helpers (tree items with the label text decode's values would print)
---------------------------------------------------------------------------------------------
local function le_int(range) return range:le_int() end
local function le_uint(range) return range:le_uint() end

-- a scaled value with its raw integer as a child
local function add_scaled(tree, abbr, raw_abbr, range, raw, scale, label, unit)
  local v = raw / scale
  local item = tree:add(F[abbr], range, v, label .. ": " .. pyfloat(v) .. (unit or ""))
  item:add(F[raw_abbr], range, raw, "Raw: " .. int_text(raw))
  return item, v
end

local function add_int(tree, abbr, range, v, label, suffix)
  return tree:add(F[abbr], range, v, label .. ": " .. int_text(v) .. (suffix or ""))
end

local function add_bits(tree, bits, range, le)
  for _, bit in ipairs(bits) do
    if le then tree:add_le(F[bit.abbr], range) else tree:add(F[bit.abbr], range) end
  end
end

local function names_of(bits, value)
  local names = {}
  for _, bit in ipairs(bits) do
    if band(value, bit.mask) ~= 0 then names[#names + 1] = bit.name end
  end
  return names
end

local function add_reserved(tree, range)
  local raw = range:bytes()
  local item = tree:add(F["reserved"], range)
  for i = 0, raw:len() - 1 do
    if raw:get_index(i) ~= 0 then
      item:add_proto_expert_info(E.reserved)
      break
    end
  end
end

-- a camera mask; its bit tree only when the value is the byte at `range` (bits = true)
local function add_cameras(tree, abbr, range, value, label, bits)
  local names = names_of(CAMERAS, value)
  local text = string.format("%s: 0x%02x", label, value)
  if #names > 0 then text = text .. " (" .. table.concat(names, ", "):lower() .. ")" end
  local item = tree:add(F[abbr], range, value, text)
  if bits then add_bits(item, CAMERAS, range, false) end
  return item
end

---------------------------------------------------------------------------------------------
-- command parameters (host bytes 70 .. S-3), one decoder per parameter kind
---------------------------------------------------------------------------------------------
-- an anomaly, worded as gcu_async words it (FieldRangeError: field, value, range, unit, detail)
local function anomaly(ctx, field, value, low, high, unit, detail)
  local msg = string.format("%s: %d is outside the allowed range [%d, %d]", field, value, low, high)
  if unit and unit ~= "" then msg = msg .. " " .. unit end
  if detail and detail ~= "" then msg = msg .. " (" .. detail .. ")" end
  ctx.err(msg)
end

-- a frame field outside the raw range V2.0.6 gives it (gcu_async's frame schemas)
local function range_anomaly(ctx, field, value, low, high, unit)
  if value < low or value > high then anomaly(ctx, field, value, low, high, unit) end
end

-- one parameter of `row` at host byte `off`: its value as decode shows it, and its raw
local function add_param(ctx, row, p, off)
  local range = ctx.r(off, p.size)
  local raw = SIGNED[p.fmt] and range:le_int() or range:le_uint()
  local label = param_label(p.name)
  local unit = p.unit ~= "" and (" " .. p.unit) or ""
  local ok = raw >= p.low and raw <= p.high
  local template = p.anomaly
  local item
  if p.segments then -- one value, several meanings (zoom_to: a ratio or a fraction)
    local seg
    for _, s in ipairs(p.segments) do
      if raw >= s.lo and raw <= s.hi then seg = s break end
    end
    if seg and seg.field then
      local v = raw / seg.scale
      item = ctx.tree:add(F[param_abbr(row, seg.field)], range, v, param_label(seg.field) .. ": "
        .. pyfloat(v) .. (seg.unit ~= "" and " " .. seg.unit or ""))
    else
      item = ctx.tree:add(range, label .. ": " .. int_text(raw) .. " (none of its meanings)")
      ok, template = false, seg and seg.anomaly or template
    end
  elseif p.switch then
    local state = p.switch[raw]
    ok = state ~= nil
    item = ctx.tree:add(F[param_abbr(row, p.name)], range, state == true, label .. ": "
      .. (state == nil and "neither (False)" or (state and "True" or "False")))
  elseif p.kind == "enum" then
    local name = (PARAM_ENUMS[p.enum] or {})[raw]
    ok = ok and name ~= nil
    item = ctx.tree:add(F[param_abbr(row, p.name)], range, name or "?",
      label .. ": " .. (name or "?") .. " (" .. int_text(raw) .. ")")
  elseif p.kind == "mask" then
    item = add_cameras(ctx.tree, param_abbr(row, p.name), range, raw, label, p.enum == "CameraMask")
  elseif p.scale ~= 1 then
    local v = raw / p.scale
    item = ctx.tree:add(F[param_abbr(row, p.name)], range, v, label .. ": " .. pyfloat(v) .. unit)
  else
    item = ctx.tree:add(F[param_abbr(row, p.name)], range, raw, label .. ": " .. int_text(raw) .. unit)
  end
  item:add(F["host.command.params_raw"], range, raw, "Raw: " .. int_text(raw))
  ctx.values[p.name] = raw
  if not ok then
    if template then
      anomaly(ctx, template.field, raw, template.low, template.high, template.unit, template.detail)
    else -- a row decode does not know: the range in raw steps of the unit
      local step = p.scale ~= 1 and pyfloat(1 / p.scale) .. " " or ""
      anomaly(ctx, p.name, raw, p.low, p.high, p.unit ~= "" and step .. p.unit or "")
    end
  end
end

-- a pair of parameters out of order (box.right left of box.left): its anomaly
local function check_rules(ctx, row)
  local v = ctx.values
  local function ref(x)
    if type(x) == "string" then return v[x] end
    return x
  end
  for _, rule in ipairs(row.rules) do
    if v[rule.above] > v[rule.below] then
      anomaly(ctx, rule.field, ref(rule.value), ref(rule.low), ref(rule.high), rule.unit,
        rule.detail)
    end
  end
end

local function params_size(row)
  local size = 0
  for _, p in ipairs(row.params) do size = size + p.size end
  return size
end

---------------------------------------------------------------------------------------------
-- frames
---------------------------------------------------------------------------------------------
local function host_main(ctx, tree)
  local r = ctx.r
  local t = tree:add(r(5, 32), "Main frame (bytes 5-36)")
  local axes = {"roll", "pitch", "yaw"}
  for k, axis in ipairs(axes) do
    local range = r(3 + 2 * k, 2)
    local raw = le_int(range)
    local item = add_int(t, "host.main.control_raw", range, raw, "Control " .. axis .. " (raw)",
      " (the mode gives its meaning: rate in 0.1/zoom deg/s, or angle in 0.01 deg)")
    item:add(F["host.main.control_as_angles_deg"], range, raw / 100,
      "As an angle: " .. pyfloat(raw / 100) .. " deg"):set_generated()
    range_anomaly(ctx, "control_" .. axis .. "_raw", raw, -18000, 18000, "")
  end
  local flags = r(11, 1):uint()
  local fitem = t:add(F["host.main.flags_raw"], r(11, 1), flags, string.format("Flags: 0x%02x", flags))
  fitem:add(F["host.main.control_valid"], r(11, 1))
  fitem:add(F["host.main.ins_valid"], r(11, 1))
  local reserved = fitem:add(F["host.main.flags_reserved"], r(11, 1))
  if band(flags, 0xFA) ~= 0 then
    reserved:add_proto_expert_info(E.reserved)
    anomaly(ctx, "flags_raw", flags, 0, 0x05, "",
      string.format("reserved bits 0x%X must be zero", band(flags, 0xFA)))
  end
  local att = {le_int(r(12, 2)), le_int(r(14, 2)), le_uint(r(16, 2))}
  local att_range = {{-18000, 17999}, {-9000, 9000}, {0, 35999}}
  for k, axis in ipairs(axes) do
    add_scaled(t, "host.main.aircraft_attitude_deg." .. axis, "host.main.aircraft_attitude_raw",
      r(10 + 2 * k, 2), att[k], 100, "Aircraft " .. axis, " deg")
    range_anomaly(ctx, "aircraft_" .. axis .. "_raw", att[k], att_range[k][1], att_range[k][2],
      "0.01 deg")
  end
  for k, axis in ipairs({"north", "east", "up"}) do
    add_scaled(t, "host.main.acceleration_m_s2." .. axis, "host.main.acceleration_raw",
      r(16 + 2 * k, 2), le_int(r(16 + 2 * k, 2)), 100, "Acceleration " .. axis, " m/s^2")
  end
  for k, axis in ipairs({"north", "east", "up"}) do
    add_scaled(t, "host.main.velocity_m_s." .. axis, "host.main.velocity_raw",
      r(22 + 2 * k, 2), le_int(r(22 + 2 * k, 2)), 100, "Velocity " .. axis, " m/s")
  end
  local req = r(30, 1):uint()
  t:add(F["host.main.subframe_request"], r(30, 1), req, string.format(
    "GCU sub frame requested: 0x%02x (%s)", req, SUBFRAME_REQUEST_NAMES[req] or "unknown"))
  add_reserved(t, r(31, 6))
end

local function host_sub(ctx, tree)
  local r = ctx.r
  local t = tree:add(r(37, 32), "Sub frame 0x01 (bytes 37-68): aircraft position")
  t:add(F["host.sub.header"], r(37, 1))
  add_scaled(t, "host.sub.latitude_deg", "host.sub.latitude_raw", r(42, 4), le_int(r(42, 4)),
    1e7, "Latitude", " deg")
  add_scaled(t, "host.sub.longitude_deg", "host.sub.longitude_raw", r(38, 4), le_int(r(38, 4)),
    1e7, "Longitude", " deg")
  range_anomaly(ctx, "longitude_raw", le_int(r(38, 4)), -1800000000, 1800000000, "1e-7 deg")
  range_anomaly(ctx, "latitude_raw", le_int(r(42, 4)), -900000000, 900000000, "1e-7 deg")
  add_scaled(t, "host.sub.altitude_m", "host.sub.altitude_raw", r(46, 4), le_int(r(46, 4)),
    1000, "Altitude", " m (MSL)")
  t:add(F["host.sub.satellites"], r(50, 1))
  local ms, week = le_uint(r(51, 4)), le_int(r(55, 2))
  local iso, doc = gnss_iso(week, ms)
  local item = t:add(F["host.sub.gnss_time_utc"], r(51, 6), iso,
    "GNSS time: " .. iso .. " (GPS time less the leap seconds)")
  item:add(F["host.sub.gnss_time_document_rule"], r(51, 6), doc,
    "Document's rule: " .. doc .. " (leap seconds ignored)")
  item:add(F["host.sub.gnss_week"], r(55, 2), week, "GNSS week: " .. int_text(week))
  item:add(F["host.sub.gnss_ms"], r(51, 4), ms, "Milliseconds of week: " .. int_text(ms))
  range_anomaly(ctx, "gnss_ms", ms, 0, 604799999, "ms")
  range_anomaly(ctx, "gnss_week", week, 0, 32767, "")
  add_scaled(t, "host.sub.relative_altitude_m", "host.sub.relative_altitude_raw", r(57, 4),
    le_int(r(57, 4)), 1000, "Relative altitude", " m")
  add_reserved(t, r(61, 8))
end

local function unknown_sub(ctx, tree, dir)
  local r = ctx.r
  local header = r(37, 1):uint()
  local t = tree:add(r(37, 32), string.format("Sub frame 0x%02x (bytes 37-68): not defined by V2.0.6", header))
  t:add(F[dir .. ".sub.header"], r(37, 1))
  t:add(F["sub.data"], r(38, 31))
end

-- bytes 37..68: standard, none (all zero) or unknown
local function sub_frame(ctx, tree, dir, standard)
  local s = ctx.s
  local header = s:byte(ctx.base + 38)
  if header == 0x01 then return standard(ctx, tree) end
  if s:sub(ctx.base + 38, ctx.base + 69) == string.rep("\0", 32) then
    tree:add(ctx.r(37, 32), "Sub frame: none (bytes 37-68 all zero)")
    return
  end
  unknown_sub(ctx, tree, dir)
end

local function host_command(ctx, tree, len)
  local r = ctx.r
  local op = r(69, 1):uint()
  local nparams = len - 72
  local name = opcode_name(op)
  local t = tree:add(F["host.command.opcode"], r(69, 1), op, string.format("Command: %s (0x%02x)", name, op))
  t:add(F["host.command.command"], r(69, 1), name):set_generated()
  ctx.summary = name
  if nparams > 0 then t:add(F["host.command.params"], r(70, nparams)) end
  local row = COMMAND_ROWS[op]
  if not row then return end -- an opcode V2.0.6 does not define: parameters kept as bytes
  local size = params_size(row)
  if nparams ~= size then
    anomaly(ctx, "params", nparams, size, size, "bytes",
      string.format("%s has %d parameter bytes", name, size))
    return
  end
  ctx.tree = t
  local off = 70
  for _, p in ipairs(row.params) do
    add_param(ctx, row, p, off)
    off = off + p.size
  end
  check_rules(ctx, row)
end

local function gcu_main(ctx, tree)
  local r = ctx.r
  local t = tree:add(r(5, 32), "Main frame (bytes 5-36)")
  local mode = r(5, 1):uint()
  local mname = MODE_NAMES[mode] or "UNKNOWN"
  local mitem = t:add(F["gcu.main.mode_raw"], r(5, 1), mode, string.format("Mode: %s (0x%02x)", mname, mode))
  mitem:add(F["gcu.main.mode"], r(5, 1), mname):set_generated()
  ctx.summary = mname
  local status = le_uint(r(6, 2))
  local names = names_of(POD_STATUS, status)
  local sitem = t:add(F["gcu.main.pod_status_raw"], r(6, 2), status, string.format(
    "Pod status: 0x%04x%s", status, #names > 0 and " (" .. table.concat(names, ", ") .. ")" or ""))
  add_bits(sitem, POD_STATUS, r(6, 2), true)
  local tracking = status % 2 == 1 -- B0, tracking: only then are the miss distances valid
  for k, axis in ipairs({"x (right +)", "y (down +)"}) do
    local miss = le_int(r(6 + 2 * k, 2))
    if tracking then
      add_int(t, "gcu.main.miss_distance", r(6 + 2 * k, 2), miss, "Miss distance " .. axis)
        :add(F["gcu.main.miss_distance_raw"], r(6 + 2 * k, 2), miss, "Raw: " .. int_text(miss))
    else
      add_int(t, "gcu.main.miss_distance_raw", r(6 + 2 * k, 2), miss,
        "Miss distance " .. axis .. ": not tracking, raw")
    end
    range_anomaly(ctx, "miss_" .. axis:sub(1, 1), miss, -1000, 1000, "")
  end
  for k, axis in ipairs({"x", "y", "z"}) do
    local angle = le_int(r(10 + 2 * k, 2))
    add_scaled(t, "gcu.main.relative_angles_deg." .. axis, "gcu.main.relative_angles_raw",
      r(10 + 2 * k, 2), angle, 100, "Relative angle " .. axis:upper(), " deg")
    range_anomaly(ctx, "relative_" .. axis .. "_raw", angle, -18000, 17999, "0.01 deg")
  end
  local att = {le_int(r(18, 2)), le_int(r(20, 2))}
  local att_range = {{-9000, 9000}, {-18000, 17999}}
  for k, axis in ipairs({"roll", "pitch"}) do
    add_scaled(t, "gcu.main.attitude_deg." .. axis, "gcu.main.attitude_raw", r(16 + 2 * k, 2),
      att[k], 100, "Camera " .. axis, " deg")
    range_anomaly(ctx, axis .. "_raw", att[k], att_range[k][1], att_range[k][2], "0.01 deg")
  end
  -- the camera yaw is a heading in [0, 360) whatever the pod sends: U16 [0, 36000) as
  -- V2.0.6 writes it; 47536-65535 only a signed S16 explains (the Z-1Pro sends its yaw
  -- signed); 36000-47535 neither: an angle past 360, wrapped
  local yaw = le_uint(r(22, 2))
  local heading = yaw
  if yaw >= 47536 then heading = yaw - 65536 end
  heading = (heading % 36000) / 100
  local yitem = t:add(F["gcu.main.attitude_deg.yaw"], r(22, 2), heading,
    "Camera yaw: " .. pyfloat(heading) .. " deg")
  yitem:add(F["gcu.main.attitude_raw"], r(22, 2), yaw, "Raw: " .. int_text(yaw))
  if yaw >= 36000 then
    anomaly(ctx, "yaw_raw", yaw, 0, 35999, "0.01 deg",
      yaw >= 47536 and YAW_SIGNED_DETAIL or YAW_PAST_TURN_DETAIL)
  end
  for k, axis in ipairs({"x", "y", "z"}) do
    add_scaled(t, "gcu.main.angular_rates_deg_s." .. axis, "gcu.main.angular_rates_raw",
      r(22 + 2 * k, 2), le_int(r(22 + 2 * k, 2)), 10, "Angular rate " .. axis:upper(), " deg/s")
  end
  add_reserved(t, r(30, 7))
end

local function flags_item(t, abbr, bits, range, value, label, width, le)
  local names = names_of(bits, value)
  local text = string.format("%s: 0x%0" .. width .. "x", label, value)
  if #names > 0 then text = text .. " (" .. table.concat(names, ", ") .. ")" end
  local item = t:add(F[abbr], range, value, text)
  add_bits(item, bits, range, le)
  return item
end

local function gcu_sub(ctx, tree)
  local r = ctx.r
  local t = tree:add(r(37, 32), "Sub frame 0x01 (bytes 37-68): pod information")
  t:add(F["gcu.sub.header"], r(37, 1))
  add_scaled(t, "gcu.sub.hardware_version", "gcu.sub.hardware_version_raw", r(38, 1),
    r(38, 1):uint(), 10, "Hardware version")
  add_scaled(t, "gcu.sub.firmware_version", "gcu.sub.firmware_version_raw", r(39, 1),
    r(39, 1):uint(), 10, "Firmware version")
  local code = r(40, 1):uint()
  local model = POD_MODEL_NAMES[code] or "UNKNOWN"
  local vendor = POD_VENDOR_NAMES[code] or string.format("unknown (code %d)", code)
  local pitem = t:add(F["gcu.sub.pod_code"], r(40, 1), code, string.format("Pod model: %s (code %d)", vendor, code))
  pitem:add(F["gcu.sub.pod_model"], r(40, 1), vendor):set_generated()
  pitem:add(F["gcu.sub.pod_model_member"], r(40, 1), model):set_generated()
  flags_item(t, "gcu.sub.fault_raw", FAULTS, r(41, 2), le_uint(r(41, 2)), "Faults", 4, true)
  local dist = le_int(r(43, 4))
  if dist > 0 then
    add_scaled(t, "gcu.sub.target_distance_m", "gcu.sub.target_distance_raw", r(43, 4), dist, 10,
      "Target distance", " m")
  else
    add_int(t, "gcu.sub.target_distance_raw", r(43, 4), dist, "Target distance: no measurement, raw")
  end
  -- the target's position: valid with its distance (no measurement, no position)
  local lat, lon, alt = le_int(r(51, 4)), le_int(r(47, 4)), le_int(r(55, 4))
  if dist > 0 then
    add_scaled(t, "gcu.sub.target_position.latitude", "gcu.sub.target_position_raw", r(51, 4),
      lat, 1e7, "Target latitude", " deg")
    add_scaled(t, "gcu.sub.target_position.longitude", "gcu.sub.target_position_raw", r(47, 4),
      lon, 1e7, "Target longitude", " deg")
    add_scaled(t, "gcu.sub.target_position.altitude", "gcu.sub.target_position_raw", r(55, 4),
      alt, 1000, "Target altitude", " m")
  else
    for _, p in ipairs({{"latitude", 51, lat}, {"longitude", 47, lon}, {"altitude", 55, alt}}) do
      add_int(t, "gcu.sub.target_position_raw", r(p[2], 4), p[3],
        "Target " .. p[1] .. ": no measurement, raw")
    end
  end
  range_anomaly(ctx, "target_longitude_raw", lon, -1800000000, 1800000000, "1e-7 deg")
  range_anomaly(ctx, "target_latitude_raw", lat, -900000000, 900000000, "1e-7 deg")
  add_scaled(t, "gcu.sub.camera1_zoom", "gcu.sub.camera1_zoom_raw", r(59, 2), le_uint(r(59, 2)),
    10, "Camera 1 zoom", " x")
  add_scaled(t, "gcu.sub.camera2_zoom", "gcu.sub.camera2_zoom_raw", r(61, 2), le_uint(r(61, 2)),
    10, "Camera 2 zoom", " x")
  flags_item(t, "gcu.sub.thermal_flags_raw", THERMAL, r(63, 1), r(63, 1):uint(), "Thermal flags", 2, false)
  local cflags = le_uint(r(64, 2))
  local citem = flags_item(t, "gcu.sub.camera_flags_raw", CAMERA_FLAGS, r(64, 2), cflags,
    "Camera flags", 4, true)
  citem:add_le(F["gcu.sub.pip_mode"], r(64, 2))
  local tz = r(66, 1):int()
  t:add(F["gcu.sub.time_zone"], r(66, 1), tz, string.format("Time zone: UTC%s%d", tz < 0 and "-" or "+",
    math.abs(tz)))
  add_reserved(t, r(67, 2))
end

local function gcu_feedback(ctx, tree, len)
  local r = ctx.r
  local op = r(69, 1):uint()
  local name = opcode_name(op)
  local t = tree:add(F["gcu.feedback.opcode"], r(69, 1), op, string.format("Feedback to: %s (0x%02x)", name, op))
  t:add(F["gcu.feedback.command"], r(69, 1), name):set_generated()
  local status = nil
  if len > MIN_LEN then
    status = r(70, 1):uint()
    t:add(F["gcu.feedback.status_raw"], r(70, 1))
  end
  -- a status this command never answers (docs/protocol-notes.md §2 "Execution status per
  -- command"); zoom answers any camera mask; opcodes V2.0.6 does not define are not checked
  if status and status ~= 0 and OPCODE_NAMES[op] and not ZOOM_OPCODES[op] then
    if THERMAL_OPCODES[op] then
      if status ~= 0x02 then
        anomaly(ctx, "status", status, 0, 2, "", "0x00 = success, 0x02 = failure")
      end
    elseif op == 0x01 then
      if status > CALIBRATION_IN_PROGRESS then
        anomaly(ctx, "status", status, 0, 2, "",
          "0x00 = success, 0x01 = failure, 0x02 = in progress")
      end
    elseif status ~= 0x01 then
      anomaly(ctx, "status", status, 0, 1, "", "0x00 = success, 0x01 = failure")
    end
  end
  if len > MIN_LEN + 1 then
    local extra = r(71, len - MIN_LEN - 1)
    t:add(F["gcu.feedback.extra_status"], extra)
    local bytes = {}
    for i = 0, extra:len() - 1 do bytes[#bytes + 1] = string.format("%02x", extra(i, 1):uint()) end
    anomaly(ctx, "status length", len - MIN_LEN, 1, 1, "bytes",
      "V2.0.6 defines one status byte; extra " .. table.concat(bytes, " "))
  end
  local result
  if status == nil then
    result = "NONE"
  elseif status == 0 then
    result = "SUCCESS"
  elseif op == 0x01 and status == CALIBRATION_IN_PROGRESS then
    result = "IN_PROGRESS"
  else
    result = "FAILED"
  end
  t:add(F["gcu.feedback.status"], status and r(70, 1) or r(69, 1), result,
    "Result: " .. result):set_generated()
  local zoom_failure = ZOOM_OPCODES[op] and status and status ~= 0
  add_cameras(t, "gcu.feedback.failed_cameras", status and r(70, 1) or r(69, 1),
    zoom_failure and status or 0, "Failed cameras", zoom_failure):set_generated()
  ctx.summary = (ctx.summary or "") .. ", feedback " .. name .. " " .. result
end

-- one packet at [start, start+len) of s; good: its CRC matched
local function dissect_packet(tvb, s, start, len, root, good, infos)
  local ctx = {s = s, base = start, values = {}}
  ctx.r = function(o, n) return tvb(start + o, n) end
  local host = u16be(s, start + 1) == HOST_HEADER
  local dir = host and "host" or "gcu"
  local tree = root:add(xfgcu, tvb(start, len))
  local problems = {}
  ctx.err = function(msg) problems[#problems + 1] = msg end
  tree:add(F["header"], ctx.r(0, 2), host and HOST_HEADER or GCU_HEADER, string.format(
    "Header: 0x%04x (%s)", host and HOST_HEADER or GCU_HEADER, host and "host -> GCU" or "GCU -> host"))
  tree:add(F["direction"], ctx.r(0, 2), host and "host_to_gcu" or "gcu_to_host"):set_generated()
  tree:add_le(F["length"], ctx.r(2, 2))
  local version = s:byte(start + 5)
  tree:add(F["version"], ctx.r(4, 1))
  if version ~= 1 and version ~= 2 then
    anomaly(ctx, "version", version, 1, 2, "",
      "V2.0.6 defines versions 1 and 2; decoded with its layout")
  end
  local ok, failure = pcall(function()
    if host then
      host_main(ctx, tree)
      sub_frame(ctx, tree, dir, host_sub)
      host_command(ctx, tree, len)
    else
      gcu_main(ctx, tree)
      sub_frame(ctx, tree, dir, gcu_sub)
      gcu_feedback(ctx, tree, len)
    end
  end)
  if not ok then
    tree:add_proto_expert_info(E.bug, "dissector error: " .. tostring(failure))
  end
  local sent = u16be(s, start + len - 1)
  local computed = crc16(s, start + 1, start + len - 2)
  local citem = tree:add(F["crc"], ctx.r(len - 2, 2), sent, string.format("CRC: 0x%04x [%s]", sent,
    good and "correct" or string.format("incorrect, should be 0x%04x", computed)))
  citem:add(F["crc.computed"], ctx.r(len - 2, 2), computed):set_generated()
  citem:add(F["crc.status"], ctx.r(len - 2, 2), good and "Good" or "Bad"):set_generated()
  if not good then citem:add_proto_expert_info(E.crc) end
  for _, msg in ipairs(problems) do
    tree:add(F["anomaly"], tvb(start, len), msg):add_proto_expert_info(E.anomaly, msg)
  end
  local what = (host and "Host->GCU " or "GCU->Host ") .. (ctx.summary or "?")
  if not good then what = what .. " [CRC MISMATCH]" elseif #problems > 0 then what = what .. " [ANOMALY]" end
  tree:append_text(string.format(", %s, %d bytes: %s", host and "host -> GCU" or "GCU -> host", len,
    (ctx.summary or "?")))
  infos[#infos + 1] = what
end

local function dissect_junk(tvb, s, start, len, root, final, infos)
  local tree = root:add(xfgcu, tvb(start, len))
  tree:append_text(string.format(": %d bytes of junk", len))
  local item = tree:add(F["junk"], tvb(start, len))
  item:add_proto_expert_info(E.junk)
  if final and len >= 4 and header_at(s, start + 1) then
    local declared = s:byte(start + 3) + s:byte(start + 4) * 256
    if declared >= MIN_LEN and declared <= MAX_LEN and start + declared > #s then
      item:add_proto_expert_info(E.truncated, string.format(
        "Truncated packet: the length says %d bytes, only %d are here", declared, #s - start))
    end
  end
  infos[#infos + 1] = string.format("%d bytes of junk", len)
end

local function set_info(pinfo, infos)
  if #infos == 0 then return end
  pinfo.cols.protocol:set("XFGCU")
  local text = table.concat(infos, " | ")
  local current = tostring(pinfo.cols.info)
  if current:find("GCU", 1, true) then
    pinfo.cols.info:append(" | " .. text)
  else
    pinfo.cols.info:set(text)
  end
end

-- dissect s (the bytes of tvb) and return the offset from which bytes wait for more (or nil)
local function dissect_bytes(tvb, pinfo, tree, s, final)
  local items, pending = items_of(s, final)
  local infos = {}
  for _, item in ipairs(items) do
    if item.kind == "junk" then
      dissect_junk(tvb, s, item.start, item.len, tree, final, infos)
    else
      dissect_packet(tvb, s, item.start, item.len, tree, item.kind == "packet", infos)
    end
  end
  set_info(pinfo, infos)
  return pending, #items
end

---------------------------------------------------------------------------------------------
-- byte streams: TCP connections and serial links, reassembled here
---------------------------------------------------------------------------------------------
-- Each direction of a TCP connection (tcp.stream, source) and of a serial link (interface,
-- direction flag) is a stream. On Wireshark's first pass, which sees the records in order,
-- the bytes a record brings are appended to what waited in that stream (TCP: in sequence
-- order, retransmitted bytes taken once, early segments held until the gap before them is
-- filled) and parsed as a stream; what may still become a packet waits for the next record.
-- The bytes each frame dissected are kept, so that later passes (a GUI click, tshark -2)
-- show exactly the same. TCP's own reassembly is not used: it hands a dissector that asks
-- for more bytes inside data it already had the whole run again, later.
local f_interface_id = Field.new("frame.interface_id")
local f_tcp_stream = Field.new("tcp.stream")
local f_tcp_seq = Field.new("tcp.seq")
local MAX_EARLY = 1024 -- TCP segments held past a gap, per stream
local GAP_PATIENCE = 8 -- segments that may arrive before a gap is skipped

local pending_bytes = {} -- stream key -> bytes waiting for more (first pass)
local next_seq = {} -- TCP stream key -> next sequence number expected
local early = {} -- TCP stream key -> {seq = bytes} past a gap
local frame_bytes = {} -- frame/stream key -> the bytes that frame dissected
local gap_age = {} -- TCP stream key -> segments seen since a gap opened

local function reset_streams()
  pending_bytes, next_seq, early, frame_bytes, gap_age = {}, {}, {}, {}, {}
end
xfgcu.init = reset_streams

local function last_value(extractor)
  local values = {extractor()}
  local last = values[#values]
  return last and last.value
end

local function drain(held, nxt, out)
  local progress = true
  while progress do
    progress = false
    for s, bytes in pairs(held) do
      if s <= nxt then
        held[s] = nil
        if s + #bytes > nxt then
          out[#out + 1] = bytes:sub(nxt - s + 1)
          nxt = s + #bytes
        end
        progress = true
      end
    end
  end
  return nxt
end

-- The new bytes a TCP segment brings to its stream, in sequence order, and whether a gap
-- was skipped. With its default preferences Wireshark's TCP does not hand retransmitted or
-- out-of-order segments to dissectors (tcp.no_subdissector_on_error): a gap that later
-- segments do not fill within GAP_PATIENCE segments is skipped, with the bytes that waited
-- before it.
local function tcp_in_order(key, seq, payload)
  local nxt = next_seq[key] or seq
  local held = early[key] or {}
  early[key] = held
  local out = {}
  local ahead = seq - nxt
  if ahead < 0 then -- a retransmission, perhaps with new bytes at its end
    payload = (-ahead < #payload) and payload:sub(-ahead + 1) or ""
    ahead = 0
  end
  local skipped = false
  if ahead > 0 then
    local count = 0
    for _ in pairs(held) do count = count + 1 end
    if held[seq] == nil and count < MAX_EARLY then held[seq] = payload end
    gap_age[key] = (gap_age[key] or 0) + 1
    if gap_age[key] > GAP_PATIENCE then
      local first
      for s in pairs(held) do if first == nil or s < first then first = s end end
      nxt, skipped = first, true
      nxt = drain(held, nxt, out)
      gap_age[key] = 0
    end
  elseif #payload > 0 then
    out[1] = payload
    nxt = drain(held, nxt + #payload, out)
    gap_age[key] = 0
  end
  next_seq[key] = nxt
  return table.concat(out), skipped
end

-- dissect one record of stream `key`; `new_bytes()` gives what it adds (first pass only)
local function dissect_stream(tvb, pinfo, tree, key, new_bytes, label)
  local fkey = pinfo.number .. "/" .. key
  local data = frame_bytes[fkey]
  local first = not pinfo.visited or data == nil
  if first then
    local bytes, skipped = new_bytes()
    data = (skipped and "" or (pending_bytes[key] or "")) .. bytes
    frame_bytes[fkey] = data
  end
  local view = tvb
  if #data > 0 and data ~= tvb:raw(0, tvb:len()) then
    view = ByteArray.new(data, true):tvb(label)
  end
  local pending, shown = dissect_bytes(view, pinfo, tree, data, false)
  if first then pending_bytes[key] = pending and data:sub(pending + 1) or "" end
  if shown == 0 then
    pinfo.cols.protocol:set("XFGCU")
    pinfo.cols.info:set(string.format("%d bytes wait for the rest of a packet",
      pending and #data - pending or 0))
  end
  return #data - tvb:len(), pending
end

---------------------------------------------------------------------------------------------
-- UDP and TCP
---------------------------------------------------------------------------------------------
local function dissect_transport(tvb, pinfo, tree)
  local n = tvb:len()
  if n == 0 then return 0 end
  local seq = last_value(f_tcp_seq)
  local stream = last_value(f_tcp_stream)
  if seq ~= nil and stream ~= nil then
    local key = string.format("tcp %s %s:%s", tostring(stream), tostring(pinfo.src),
      tostring(pinfo.src_port))
    local start = tonumber(tostring(seq))
    dissect_stream(tvb, pinfo, tree, key, function()
      return tcp_in_order(key, start, tvb:raw(0, n))
    end, "TCP bytes (reassembled)")
    return n
  end
  dissect_bytes(tvb, pinfo, tree, tvb:raw(0, n), true) -- a datagram: its end ends it
  return n
end
xfgcu.dissector = dissect_transport

-- the payload holds at least one whole packet: header, length and CRC
local function holds_packet(tvb)
  local n = tvb:len()
  if n < MIN_LEN then return false end
  local packets = reference_parse(tvb:raw(0, n), true)
  return #packets > 0
end

-- Wireshark drops errors raised in heuristic dissectors silently: report them as an item
local function guarded(heuristic)
  return function(tvb, pinfo, tree)
    local ok, result = pcall(heuristic, tvb, pinfo, tree)
    if ok then return result end
    tree:add(xfgcu, tvb()):add_proto_expert_info(E.bug, "dissector error: " .. tostring(result))
    return true
  end
end

local heuristic_udp = guarded(function(tvb, pinfo, tree)
  if not holds_packet(tvb) then return false end
  dissect_transport(tvb, pinfo, tree)
  return true
end)

local heuristic_tcp = guarded(function(tvb, pinfo, tree)
  if not holds_packet(tvb) then return false end
  pinfo.conversation = xfgcu -- the rest of this connection is ours
  dissect_transport(tvb, pinfo, tree)
  return true
end)

---------------------------------------------------------------------------------------------
-- serial links captured by gcu_async: DLT_USER5, one record per read or write
---------------------------------------------------------------------------------------------
xfgcu_serial.init = reset_streams

function xfgcu_serial.dissector(tvb, pinfo, tree)
  local n = tvb:len()
  local dir = pinfo.p2p_dir == P2P_DIR_SENT and "sent"
    or (pinfo.p2p_dir == P2P_DIR_RECV and "received" or "unknown")
  local key = string.format("serial %s %s", tostring(last_value(f_interface_id) or 0), dir)
  local t = tree:add(xfgcu_serial, tvb())
  t:append_text(string.format(", %s by the capturing side", dir))
  t:add(serial_f.direction, tvb(), dir):set_generated()
  t:add(serial_f.chunk, tvb(), n):set_generated()
  local carried = dissect_stream(tvb, pinfo, tree, key, function() return tvb:raw(0, n) end,
    "Serial bytes (reassembled)")
  if carried > 0 then t:add(serial_f.pending, tvb(), carried):set_generated() end
  return n
end

---------------------------------------------------------------------------------------------
-- registration
---------------------------------------------------------------------------------------------
local udp_port = DissectorTable.get("udp.port")
udp_port:add(2337, xfgcu)
udp_port:add(2338, xfgcu)
local tcp_port = DissectorTable.get("tcp.port")
tcp_port:add(2332, xfgcu)
udp_port:add_for_decode_as(xfgcu)
tcp_port:add_for_decode_as(xfgcu)
DissectorTable.get("wtap_encap"):add(SERIAL_WTAP, xfgcu_serial)
xfgcu:register_heuristic("udp", heuristic_udp)
xfgcu:register_heuristic("tcp", heuristic_tcp)
