-- The dissector's engine: the same for every spec. It reads the SPECS tables above, which
-- `busspec dissector` generated from each spec's IR, and follows busspec's own decoder
-- (`busspec_model::interp`) and JSON printer (`busspec_json::print`).

local floor, huge = math.floor, math.huge
local fmt, concat = string.format, table.concat

-- Integers of any size, for exact physical values: limbs of 10^7, least significant first,
-- `n` true when negative. Every limb product stays below 2^53.
local BASE = 10000000

local function bn_norm(a)
  while #a > 0 and a[#a] == 0 do a[#a] = nil end
  if #a == 0 then a.n = false end
  return a
end

local function bn_int(x)
  local a = { n = x < 0 }
  x = math.abs(x)
  while x > 0 do
    local r = x % BASE
    a[#a + 1] = r
    x = (x - r) / BASE
  end
  return bn_norm(a)
end

local function bn_parse(s)
  local a = { n = false }
  if s:sub(1, 1) == "-" then a.n = true; s = s:sub(2) end
  local i = #s
  while i >= 1 do
    local j = i - 6
    if j < 1 then j = 1 end
    a[#a + 1] = tonumber(s:sub(j, i))
    i = j - 1
  end
  return bn_norm(a)
end

local function bn_cmpabs(a, b)
  if #a ~= #b then return (#a < #b) and -1 or 1 end
  for i = #a, 1, -1 do
    if a[i] ~= b[i] then return (a[i] < b[i]) and -1 or 1 end
  end
  return 0
end

local function bn_add(a, b)
  local r = {}
  if a.n == b.n then
    local c = 0
    for i = 1, math.max(#a, #b) do
      local s = (a[i] or 0) + (b[i] or 0) + c
      if s >= BASE then r[i] = s - BASE; c = 1 else r[i] = s; c = 0 end
    end
    if c > 0 then r[#r + 1] = c end
    r.n = a.n
  else
    local x, y = a, b
    if bn_cmpabs(a, b) < 0 then x, y = b, a end
    local c = 0
    for i = 1, #x do
      local s = x[i] - (y[i] or 0) - c
      if s < 0 then r[i] = s + BASE; c = 1 else r[i] = s; c = 0 end
    end
    r.n = x.n
  end
  return bn_norm(r)
end

local function bn_mul(a, b)
  local r = {}
  for i = 1, #a + #b do r[i] = 0 end
  for i = 1, #a do
    local c, ai = 0, a[i]
    for j = 1, #b do
      local s = r[i + j - 1] + ai * b[j] + c
      c = floor(s / BASE)
      r[i + j - 1] = s - c * BASE
    end
    local k = i + #b
    while c > 0 do
      local s = r[k] + c
      c = floor(s / BASE)
      r[k] = s - c * BASE
      k = k + 1
    end
  end
  r.n = (a.n ~= b.n)
  return bn_norm(r)
end

-- Quotient and remainder (of the magnitude) by a positive integer below 9 * 10^8.
local function bn_divsmall(a, d)
  local q, rem = { n = a.n }, 0
  for i = #a, 1, -1 do
    local cur = rem * BASE + a[i]
    local qi = floor(cur / d)
    q[i] = qi
    rem = cur - qi * d
  end
  return bn_norm(q), rem
end

local function bn_str(a)
  if #a == 0 then return "0" end
  local parts = { fmt("%d", a[#a]) }
  for i = #a - 1, 1, -1 do parts[#parts + 1] = fmt("%07d", a[i]) end
  return (a.n and "-" or "") .. concat(parts)
end

local I128_MAX = "170141183460469231731687303715884105727"

-- A double rounded to the nearest f32 (ties to even), as a double.
local function to_f32(d)
  if d ~= d or d == huge or d == -huge or d == 0 then return d end
  local a = math.abs(d)
  local e = floor(math.log(a) / math.log(2))
  if 2 ^ e > a then e = e - 1 elseif 2 ^ (e + 1) <= a then e = e + 1 end
  if e < -126 then e = -126 end
  local ulp = 2 ^ (e - 23)
  local q = a / ulp
  local r = floor(q)
  local frac = q - r
  if frac > 0.5 or (frac == 0.5 and r % 2 == 1) then r = r + 1 end
  local v = r * ulp
  if v >= 2 ^ 128 then v = huge end
  if d < 0 then return -v end
  return v
end

-- The shortest digits of a finite non-zero double that read back to it (`single`: to the same
-- f32), as Rust finds them: its sign, the digits (no trailing zeros) and the first digit's
-- power of ten. Where the value lies halfway between two shortest texts, Rust takes the one
-- further from zero (`%e` rounds half to even): the exact digits, rounded up.
local function shortest_digits(x, single)
  local s, p
  for q = 0, 16 do
    p = q
    s = fmt("%." .. p .. "e", x)
    local back = tonumber(s)
    if single then back = to_f32(back) end
    if back == x then break end
  end
  local sign, m, e = s:match("^(-?)([%d%.]+)e([-+]%d+)$")
  local digits = m:gsub("%.", "")
  e = tonumber(e)
  local exact = fmt("%." .. (p + 21) .. "e", x):match("^-?([%d%.]+)e"):gsub("%.", "")
  if exact:sub(p + 2, p + 2) == "5" and exact:sub(p + 3):match("^0*$") then
    local up, carry = {}, 1
    for i = p + 1, 1, -1 do
      local d = tonumber(exact:sub(i, i)) + carry
      carry = (d == 10) and 1 or 0
      up[i] = tostring(d % 10)
    end
    digits = concat(up)
    if carry == 1 then
      digits = "1" .. digits
      e = e + 1
    end
  end
  digits = digits:gsub("0+$", "")
  if digits == "" then digits = "0" end
  return sign, digits, e
end

-- Digits whose first is at 10^e, written out without an exponent (`point`: with ".0" where
-- there is no fraction).
local function positional(sign, digits, e, point)
  local out
  if e >= 0 then
    if #digits <= e + 1 then
      out = digits .. string.rep("0", e + 1 - #digits) .. (point and ".0" or "")
    else
      out = digits:sub(1, e + 1) .. "." .. digits:sub(e + 2)
    end
  else
    out = "0." .. string.rep("0", -e - 1) .. digits
  end
  return sign .. out
end

-- A double as Rust's `{}` prints it: the shortest digits that read back, never an exponent.
local function rust_f64(x)
  if x ~= x then return "NaN" end
  if x == huge then return "inf" end
  if x == -huge then return "-inf" end
  if x == 0 then return (1 / x < 0) and "-0" or "0" end
  local sign, digits, e = shortest_digits(x, false)
  return positional(sign, digits, e, false)
end

-- A finite float as Rust's `{:?}` prints it (`single`: an f32): the shortest digits, with an
-- exponent below 1e-4 and from 1e16 on, and a point otherwise.
local function rust_debug_float(x, single)
  if x == 0 then return (1 / x < 0) and "-0.0" or "0.0" end
  local sign, digits, e = shortest_digits(x, single)
  local a = math.abs(x)
  if a < 1e-4 or a >= 1e16 then
    local frac = digits:sub(2)
    return sign .. digits:sub(1, 1) .. (frac ~= "" and ("." .. frac) or "") .. "e" .. e
  end
  return positional(sign, digits, e, true)
end
-- `digits` (an integer's text) divided by 10^k, as Rust's `Rational` prints it: no trailing
-- zeros; nil where Rust's i128 arithmetic would not hold it (it then prints the double).
local function decimal(digits, k)
  local sign = ""
  if digits:sub(1, 1) == "-" then sign = "-"; digits = digits:sub(2) end
  if #digits <= k then digits = string.rep("0", k + 1 - #digits) .. digits end
  local int, frac = digits:sub(1, #digits - k), digits:sub(#digits - k + 1)
  frac = frac:gsub("0+$", "")
  local scaled = (int .. frac):gsub("^0+", "")
  if #frac > 38 or #scaled > #I128_MAX or (#scaled == #I128_MAX and scaled > I128_MAX) then
    return nil
  end
  if frac == "" then
    if int == "0" then sign = "" end
    return sign .. int
  end
  return sign .. int .. "." .. frac
end

-- A raw value's physical value in its unit, as busspec's JSON prints it (`physical_text`).
local function physical(u, raw)
  local N = bn_add(bn_mul(bn_int(raw), u.A), u.B)
  if u.r then
    local q, rem = N, 0
    if u.r ~= 1 then q, rem = bn_divsmall(N, u.r) end
    if rem == 0 then
      local text = decimal(bn_str(bn_mul(q, u.M)), u.k)
      if text then return text end
    end
  end
  return rust_f64(tonumber(bn_str(N)) / u.Df)
end

-- Where byte i of a word-swapped number of w bytes travels (`number::swap_index`).
local function swap_index(i, w)
  return (w / 2 - 1 - floor(i / 2)) * 2 + i % 2
end

-- The value bytes of a 64-bit or float field, most significant first: its byte order
-- undone, and a word-swapped number's 16-bit words put back.
local function wide_bytes(f, b, at)
  local w, v = f.width, {}
  for i = 0, w - 1 do
    local j = i
    if f.swap then j = swap_index(i, w) end
    local x = b[at + j] or 0
    if f.order == "big" then v[i + 1] = x else v[w - i] = x end
  end
  return v
end

local function word32(v, from)
  return ((v[from] * 256 + v[from + 1]) * 256 + v[from + 2]) * 256 + v[from + 3]
end

-- A 64-bit pattern (two 32-bit words) as a decimal integer, signed or not.
local function int64_text(hi, lo, signed)
  local two32 = bn_int(4294967296)
  local n = bn_add(bn_mul(bn_int(hi), two32), bn_int(lo))
  if signed and hi >= 2147483648 then
    local two64 = bn_mul(two32, two32)
    two64.n = true
    n = bn_add(n, two64)
  end
  return bn_str(n)
end

-- A 64-bit or float field's value: `json` as busspec's JSON prints it (`number::NumKind::
-- text`, a non-finite float a string), `text` as its errors print it, `raw` its raw value (the
-- bits as an i64, an f32's zero-extended), and `x` (a float, as a double) or `n` (an integer,
-- a big number) to compare with its range.
local function wide_value(f, b, at)
  local v = wide_bytes(f, b, at)
  local function float(x, special)
    if special then return { json = '"' .. special .. '"', text = special, x = x } end
    return { json = rust_debug_float(x, f.wide == "f32"), x = x }
  end
  -- A float from its sign, biased exponent and fraction (`bits` of them, `top` the all-ones
  -- exponent), with the text of its NaN.
  local function ieee(neg, e, frac, bits, top, nan)
    if e == top and frac ~= 0 then return float(0 / 0, nan) end
    if e == top then return float(neg and -huge or huge, neg and "-inf" or "inf") end
    local bias, x = (top - 1) / 2, nil
    if e == 0 then x = frac * 2 ^ (1 - bias - bits) else x = (2 ^ bits + frac) * 2 ^ (e - bias - bits) end
    return float(neg and -x or x)
  end
  local out
  if f.wide == "f32" then
    local w = word32(v, 1)
    local nan = (w == 2143289344) and "NaN" or fmt("NaN:0x%08X", w)
    out = ieee(w >= 2147483648, floor(w / 8388608) % 256, w % 8388608, 23, 255, nan)
    out.raw = fmt("%d", w)
  else
    local hi, lo = word32(v, 1), word32(v, 5)
    local raw = int64_text(hi, lo, true)
    if f.wide == "u64" or f.wide == "i64" then
      local text = (f.wide == "u64") and int64_text(hi, lo, false) or raw
      out = { json = text, n = bn_parse(text) }
    else
      local nan = (hi == 2146959360 and lo == 0) and "NaN" or fmt("NaN:0x%08X%08X", hi, lo)
      local frac = (hi % 1048576) * 4294967296 + lo
      out = ieee(hi >= 2147483648, floor(hi / 1048576) % 2048, frac, 52, 2047, nan)
    end
    out.raw = raw
  end
  out.text = out.text or out.json
  return out
end

-- Whether a 64-bit or float value lies in its field's range (`wrange`: the bounds' texts, and
-- a float's as numbers): a NaN lies in none.
local function wide_within(f, w)
  local r = f.wrange
  if not r then return true end
  if w.x then return w.x >= r[3] and w.x <= r[4] end
  local function cmp(a, c)
    if a.n ~= c.n then return a.n and -1 or 1 end
    local m = bn_cmpabs(a, c)
    if a.n then return -m end
    return m
  end
  return cmp(w.n, bn_parse(r[1])) >= 0 and cmp(w.n, bn_parse(r[2])) <= 0
end

local function numtext(v)
  return fmt("%d", v)
end

-- A JSON string of text whose bytes are characters U+0000..U+00FF (a field's ASCII bytes).
local function json_bytes(s)
  local out = { '"' }
  for i = 1, #s do
    local c = s:byte(i)
    if c == 34 then out[#out + 1] = '\\"'
    elseif c == 92 then out[#out + 1] = "\\\\"
    elseif c == 8 then out[#out + 1] = "\\b"
    elseif c == 12 then out[#out + 1] = "\\f"
    elseif c == 10 then out[#out + 1] = "\\n"
    elseif c == 13 then out[#out + 1] = "\\r"
    elseif c == 9 then out[#out + 1] = "\\t"
    elseif c < 32 then out[#out + 1] = fmt("\\u%04x", c)
    elseif c >= 128 then out[#out + 1] = string.char(192 + floor(c / 64), 128 + c % 64)
    else out[#out + 1] = string.char(c) end
  end
  out[#out + 1] = '"'
  return concat(out)
end

-- A JSON string of UTF-8 text (names from the spec).
local function json_name(s)
  local out = s:gsub('[%c"\\]', function(ch)
    local c = ch:byte()
    if c == 34 then return '\\"' elseif c == 92 then return "\\\\"
    elseif c == 8 then return "\\b" elseif c == 12 then return "\\f"
    elseif c == 10 then return "\\n" elseif c == 13 then return "\\r"
    elseif c == 9 then return "\\t" elseif c < 32 then return fmt("\\u%04x", c) end
    return ch
  end)
  return '"' .. out .. '"'
end

local function read_uint(b, at, width, order)
  local v = 0
  if order == "big" then
    for i = 0, width - 1 do v = v * 256 + (b[at + i] or 0) end
  else
    for i = width - 1, 0, -1 do v = v * 256 + (b[at + i] or 0) end
  end
  return v
end

local function write_uint(b, at, width, order, v)
  for i = 0, width - 1 do
    local byte = floor(v / 2 ^ (8 * i)) % 256
    if order == "big" then b[at + width - 1 - i] = byte else b[at + i] = byte end
  end
end

-- The frame unescaped (`framing.escaping`), as busspec unescapes it: a table of bytes from 0,
-- its length and how many bytes escaping added; or nil, the offset and the words of a bad
-- escape. Where the spec computes the length field and checksum on the escaped bytes, they are
-- rewritten so that they are right for the unescaped frame exactly where the escaped ones are.
local function unescape(P, w, n, e)
  e = e or P.escaping
  local from, to = e.from, n - e.tail
  if to < from then return w, n, 0 end
  local out, k = {}, 0
  local function push(x) out[k] = x; k = k + 1 end
  for i = 0, from - 1 do push(w[i]) end
  if e.kind == "bytes" then
    local i = from
    while i < to do
      local x = w[i]
      if x == e.escape then
        local nx = w[i + 1] or 0
        local raw
        for j, r in ipairs(e.rep) do if r == nx then raw = e.raw[j] end end
        if raw == nil or i + 1 >= to then
          return nil, i, fmt("0x%02X followed by 0x%02X", x, nx)
        end
        push(raw)
        i = i + 2
      else
        for _, r in ipairs(e.raw) do
          if r == x then return nil, i, fmt("0x%02X not escaped", x) end
        end
        push(x)
        i = i + 1
      end
    end
  elseif e.kind == "insert" then
    local i, since, pl = from, k, #e.after
    while i < to do
      push(w[i])
      i = i + 1
      if k - since >= pl then
        local match = true
        for j = 1, pl do
          if out[k - pl + j - 1] ~= e.after[j] then match = false end
        end
        if match then
          local f = w[i]
          if f == nil then
            return nil, i, fmt("expected inserted byte 0x%02X, found the frame's end", e.byte)
          end
          if f ~= e.byte or i >= to then
            return nil, i, fmt("expected inserted byte 0x%02X, found 0x%02X", e.byte, f)
          end
          i = i + 1
          since = k
        end
      end
    end
  else
    if from == to then return nil, from, "no COBS block before the end byte" end
    local i, full = from, false
    while i < to do
      local code = w[i]
      if code == 0 then return nil, i, "COBS block holds 0x00" end
      if i + code > to then return nil, i, fmt("COBS block 0x%02X runs past the end byte", code) end
      if full and code == 1 and i + 1 == to then
        return nil, i, "COBS block 0x01 after a full block ends the frame"
      end
      for j = i + 1, i + code - 1 do
        if w[j] == 0 then return nil, j, "COBS block holds 0x00" end
        push(w[j])
      end
      i = i + code
      full = (code == 255)
      if i < to and not full then push(0) end
    end
  end
  for i = to, n - 1 do push(w[i]) end
  local added = n - k
  if e.computed_escaped and added > 0 then
    if e.length_at then
      local v = read_uint(w, e.length_at, e.length_width, P.order)
      write_uint(out, e.length_at, e.length_width, P.order, (v - added) % 2 ^ (8 * e.length_width))
    end
    local ck = P.checksum
    if ck.len > 0 then
      local at = n - e.checksum_from_end
      local good = ck.fn(w, ck.covers_from, at) == read_uint(w, at, ck.len, ck.order)
      local own_at = k - e.checksum_from_end
      local own = ck.fn(out, ck.covers_from, own_at)
      if not good then
        if own % 2 == 0 then own = own + 1 else own = own - 1 end
      end
      write_uint(out, own_at, ck.len, ck.order, own)
      -- Shown and checked as the escaped bytes carry it.
      local wire_ck = { at = at, expected = ck.fn(w, ck.covers_from, at), found = read_uint(w, at, ck.len, ck.order) }
      return out, k, added, wire_ck
    end
  end
  return out, k, added
end

local function sign_extend(v, bits)
  if bits > 0 and v >= 2 ^ (bits - 1) then return v - 2 ^ bits end
  return v
end

-- The number binary-coded decimal `u` stands for; nil where a digit is above 9.
local function from_bcd(u)
  local v, scale = 0, 1
  while u > 0 do
    local d = u % 16
    if d > 9 then return nil end
    v = v + d * scale
    scale = scale * 10
    u = floor(u / 16)
  end
  return v
end

-- A whole field's value: unsigned as read, and as its type reads it (a BCD field's decimal
-- number, both).
local function int_of(f, b, at)
  if f.ascii then return 0, 0 end
  local u
  if f.swap then
    -- A word-swapped number: its 16-bit words put back in its byte order first.
    local w = {}
    for i = 0, f.width - 1 do w[i] = b[at + swap_index(i, f.width)] end
    u = read_uint(w, 0, f.width, f.order)
  else
    u = read_uint(b, at, f.width, f.order)
  end
  if f.bcd then
    local v = from_bcd(u) or 0
    return v, v
  end
  if f.signed then return u, sign_extend(u, 8 * f.width) end
  return u, u
end

local function bit_value(container, bf)
  local w = bf.msb - bf.lsb + 1
  local v = floor(container / 2 ^ bf.lsb) % 2 ^ w
  if bf.signed then return sign_extend(v, w) end
  return v
end

local function has_bit(v, bit)
  if v < 0 then
    if bit >= 32 then return true end
    v = v + 2 ^ 32
  end
  return floor(v / 2 ^ bit) % 2 == 1
end

local function apply(rel, v)
  local n, d = v * rel.mul, rel.div
  if d < 1 then d = 1 end
  if n >= 0 then return math.ceil(n / d) end
  return -floor(-n / d)
end

local function read_elements(f, b, from, to)
  local out = {}
  if f.rep.bit then
    for i = from, to - 1 do
      local x = b[i]
      for k = 0, 7 do out[#out + 1] = floor(x / 2 ^ k) % 2 end
    end
    return out
  end
  local w = f.width
  if w < 1 then w = 1 end
  local i = from
  while i + w <= to do
    local _, v = int_of(f, b, i)
    out[#out + 1] = v
    i = i + w
  end
  return out
end

-- The elements of a packed field (`f.pk`) from byte `at`, and whether the bits after its last
-- element are all 0 (`ir::Packed::read`, `padding_clear`).
-- One element of a list of a fixed count (`f.pk.whole`): the field, `ew` bytes wide.
local function element_of(f)
  return setmetatable({ width = f.pk.ew }, { __index = f })
end

-- The elements of a list of a fixed count of floats or 64-bit integers: each as `wide_value`
-- reads it, and the byte where it starts.
local function read_wide_elements(f, b, at)
  local e, out = element_of(f), {}
  for k = 0, f.pk.count - 1 do
    local from = at + k * f.pk.ew
    out[#out + 1] = { w = wide_value(e, b, from), at = from }
  end
  return e, out
end

-- The elements of a repeated field of floats or 64-bit integers from byte `at` up to `stop`:
-- each as `wide_value` reads it (the field is one element wide), and the byte where it starts.
local function read_wide_list(f, b, at, stop)
  local out = {}
  local k = at
  while k + f.width <= stop do
    out[#out + 1] = { w = wide_value(f, b, k), at = k }
    k = k + f.width
  end
  return out
end

local function read_packed(f, b, at)
  local out, p = {}, f.pk
  if p.whole then
    -- Elements of whole bytes (a list of a fixed count): each as a field of its type reads.
    local e = element_of(f)
    for k = 0, p.count - 1 do
      local _, v = int_of(e, b, at + k * p.ew)
      out[#out + 1] = v
    end
    return out
  end
  for k = 0, p.count - 1 do
    local v, weight = 0, 1
    for j = 0, p.bits - 1 do
      local s = k * p.bits + j
      local x = b[at + floor(s / 8)] or 0
      if p.lsb then
        v = v + (floor(x / 2 ^ (s % 8)) % 2) * weight
        weight = weight * 2
      else
        v = v * 2 + floor(x / 2 ^ (7 - s % 8)) % 2
      end
    end
    out[#out + 1] = floor(v)
  end
  return out
end

local function packed_padding_clear(f, b, at)
  local p = f.pk
  for s = p.count * p.bits, f.width * 8 - 1 do
    local x = b[at + floor(s / 8)] or 0
    local sh = 7 - s % 8
    if p.lsb then sh = s % 8 end
    if floor(x / 2 ^ sh) % 2 == 1 then return false end
  end
  return true
end

local function elements_len(f, n)
  if f.rep.bit then return math.ceil(n / 8) end
  -- Text up to a terminator: its characters and the terminator after them.
  if f.rep.count == "until" then return n + 1 end
  return n * f.width
end

-- A repeated record's width in this frame and its fields, the last as many bytes wide as
-- the field `f.sized.by` (at `at[by]`) says where one gives it (nil where that is outside
-- 1..=most: `interp::shape` refuses it); otherwise its width and fields as they are.
local function record_layout(m, f, b, at)
  local s = f.sized
  if not s then return f.width, f.rec end
  local c = m.fields[s.by]
  local v = read_uint(b, at[s.by], c.width, c.order)
  if v < 1 or v > s.most then return nil end
  local rec = {}
  for j, g in ipairs(f.rec) do
    if j == #f.rec then
      local h = {}
      for k, x in pairs(g) do h[k] = x end
      h.width = v
      rec[j] = h
    else
      rec[j] = g
    end
  end
  return s.fixed + v, rec
end

-- Where each field of message m sits in the frame (`at[i]`, byte offsets as `b` indexes them)
-- and the bytes each repeated field's elements take (`len[i]`), the lists counted in wire
-- order; nil where the frame's length, a count field and the bounds disagree (`interp::shape`).
-- The last list takes exactly what the frame's length leaves.
local function shape(m, b, n)
  local at, len = {}, {}
  local rest = n - m.len
  if rest < 0 then return nil end
  local lists, seen, shift = 0, 0, 0
  for _, f in ipairs(m.fields) do
    if f.rep then lists = lists + 1 end
  end
  local opt = 0
  for i, f in ipairs(m.fields) do
    at[i] = m.payload_at + f.offset + shift
    local r = f.rep
    if f.opt then
      -- An optional field: its bytes where its condition holds (it ends the payload; the
      -- field its condition reads sits before it).
      local c = m.fields[f.opt.by]
      local v = read_uint(b, at[f.opt.by], c.width, c.order)
      local on
      if f.opt.bit then on = has_bit(v, f.opt.bit) else on = v == f.opt.eq end
      len[i] = on and f.width or 0
      opt = opt + len[i]
      shift = shift + len[i]
    elseif r then
      seen = seen + 1
      local last = seen == lists
      local w = f.width
      if f.sized then
        w = record_layout(m, f, b, at)
        if not w then return nil end
      end
      if w < 1 then w = 1 end
      local count
      if r.count == "to_end" then
        -- End bytes alone delimit the frame (`m.delim`): from the list's first byte on, the
        -- first are the frame's own.
        if m.delim then
          for k = 0, n - #m.delim - at[i] - 1 do
            local all = true
            for j, e in ipairs(m.delim) do
              if b[at[i] + k + j - 1] ~= e then
                all = false
                break
              end
            end
            if all then return nil end
          end
        end
        if not r.bit and rest % w ~= 0 then return nil end
        count = r.bit and rest * 8 or floor(rest / w)
      elseif r.count == "until" then
        -- Characters up to the first terminator byte (`r.by`) the frame's length leaves.
        for k = 0, rest - 1 do
          if b[at[i] + k] == r.by then
            count = k
            break
          end
        end
        if not count then return nil end
        -- The last list takes exactly what the frame leaves, as busspec's decode: without a
        -- length field its terminator alone ends the frame (RoboClaw's firmware version).
        if last and count + 1 ~= rest then return nil end
      elseif r.count == "fixed" then
        -- Records of a fixed count (`r.by` of them): as a count field saying so would.
        local bytes = elements_len(f, r.by)
        if (last and bytes ~= rest) or bytes > rest then return nil end
        count = r.by
      else
        local c = m.fields[r.by]
        local v = read_uint(b, at[r.by], c.width, c.order)
        if r.count == "elements" then
          local bytes = elements_len(f, v)
          if (last and bytes ~= rest) or bytes > rest then return nil end
          count = v
        else
          if (not r.bit and v % w ~= 0) or (last and v ~= rest) or v > rest then return nil end
          count = r.bit and v * 8 or floor(v / w)
        end
      end
      local lo, hi = r.min, r.max
      if r.bit then lo, hi = math.ceil(lo / 8) * 8, math.ceil(hi / 8) * 8 end
      if count < lo or count > hi then return nil end
      len[i] = f.sized and count * w or elements_len(f, count)
      rest = rest - len[i]
      shift = shift + len[i]
    end
  end
  if m.optional and n ~= m.len + opt then return nil end
  return at, len
end

-- `shape`, or for a frame it does not fit, every field at its offset and a list to the
-- payload's end `pend`.
local function places(m, b, n, pend)
  local at, len = shape(m, b, n)
  if at then return at, len end
  at, len = {}, {}
  for i, f in ipairs(m.fields) do
    at[i] = m.payload_at + f.offset
    if f.rep then len[i] = math.max(pend - at[i], 0) end
    if f.opt then len[i] = 0 end
  end
  return at, len
end

-- The end bytes and the bytes after the payload of a frame of direction dir: a response's own
-- where they differ by direction (`response_ends`, F.Port's uplink without the flags).
local function ends_of(P, dir)
  if dir == "response" and P.response_ends then return P.response_ends end
  return P.ends
end

local function trailer_by(P, dir)
  if dir == "response" and P.response_trailer then return P.response_trailer end
  return P.trailer
end

local function end_at(P, n, dir)
  if P.end_first then return n - trailer_by(P, dir) end
  return n - #ends_of(P, dir)
end

local function checksum_at(P, n, dir)
  -- Before the bytes it covers (SBF's CRC at offset 2): there whatever the length.
  if P.checksum.lead then return P.checksum.lead end
  if P.end_first then return n - P.checksum.len end
  return n - P.checksum.len - #ends_of(P, dir)
end

-- The bytes after message m's payload: none for a message without a checksum
-- (`checksum: none`, validated without end bytes).
local function trailer_of(P, m)
  if m.unchecked then return 0 end
  return trailer_by(P, m.dir)
end

-- Whether the frame has message m's shape: start, code, end bytes, length field and length.
-- The request's whole number fields by name (raw values), for the rules of its replies that
-- follow from them.
local function request_values(P, m, b, n)
  local vals = {}
  local pos = places(m, b, n, n - trailer_of(P, m))
  for i, f in ipairs(m.fields) do
    if not (f.rep or f.pk or f.wide or f.ascii or f.opt or f.rec or f.bcd) and #f.bits == 0 then
      local _, v = int_of(f, b, pos[i])
      vals[f.name] = v
    end
  end
  return vals
end

-- Whether reply m's values that follow from its request's (`follows: {request}`, a count from
-- the request) do, as busspec's pairing checks them; true where it has none, or no values
-- of the request were kept.
local function follows_request(P, m, b, n, vals)
  if not vals then return true end
  local pos, lens = places(m, b, n, n - trailer_of(P, m))
  for i, f in ipairs(m.fields) do
    if f.freq and vals[f.freq.name] ~= nil then
      local _, v = int_of(f, b, pos[i])
      if v ~= apply(f.freq, vals[f.freq.name]) then return false end
    end
    local req = f.rep and f.rep.req
    if req and vals[req.name] ~= nil then
      local e = apply(req, vals[req.name])
      local want
      if e < 0 then
        want = -1
      elseif f.rep.bit then
        want = math.ceil(e / 8)
      else
        want = e * math.max(f.width, 1)
      end
      if want ~= lens[i] then return false end
    end
  end
  return true
end

local function structural(P, m, b, n)
  if n < m.len or n > m.max_len then return false end
  if m.start_at then
    local sync = (m.dir == "response") and P.response_sync or P.sync
    for _, at in ipairs({ m.start_at, m.start_again or false }) do
      if at then
        for i, s in ipairs(sync) do
          if b[at + i - 1] ~= s then return false end
        end
      end
    end
  end
  if m.code_at + #m.code + trailer_of(P, m) > n then return false end
  for i, c in ipairs(m.code) do
    if b[m.code_at + i - 1] ~= c then return false end
  end
  local e = end_at(P, n, m.dir)
  for i, x in ipairs(ends_of(P, m.dir)) do
    if b[e + i - 1] ~= x then return false end
  end
  local rule = P.rules[m.dir]
  if rule then
    local want = -1
    if n >= rule.head_len then want = rule.grows and (n + rule.k) or rule.k end
    if read_uint(b, rule.at, rule.width, P.order) ~= want then return false end
    if rule.again and read_uint(b, rule.again, rule.width, P.order) ~= want then return false end
  end
  if m.variable and not shape(m, b, n) then return false end
  return true
end

local function range_violation(f, bf, v)
  local range
  if bf then range = bf.range else range = f.range end
  if not range then return nil end
  if v >= range[1] and v <= range[2] then return nil end
  if not bf and f.special and f.special[v] then return nil end
  return range
end

local function out_of_range(m, name, at, v, range)
  return fmt("%s.%s at offset %d is %s, outside its range %s..=%s", m.name, name, at, numtext(v),
    numtext(range[1]), numtext(range[2]))
end

-- The rules of the spec the frame breaks as message m, worded as busspec's strict decoding
-- words them and in its order (address, broadcast, each field), into `soft`; returns true
-- where the frame is not message m at all (a constant, or a value that must follow or repeat
-- another field, differs).
local function misfit(P, m, b, n, soft)
  local A = P.address
  local address = m.address_at and b[m.address_at] or 0
  if m.address_at and A then
    local ok = (address >= A.min and address <= A.max) or address == A.broadcast or address == A.host
    if not ok then
      soft[#soft + 1] = fmt("address 0x%02X at offset %d is outside the device range 0x%02X..=0x%02X and is not the broadcast or host address",
        address, m.address_at, A.min, A.max)
    end
  end
  if m.dir == "request" and A and A.broadcast == address and not m.broadcast_ok then
    local code = (#m.code == 0) and " (no code)" or (" (code " .. m.code_hex .. ")")
    soft[#soft + 1] = fmt("%s%s does not accept the broadcast address 0x%02X", m.name, code, address)
  end
  local pend = n - trailer_of(P, m)
  local pos, lens = places(m, b, n, pend)
  for i, f in ipairs(m.fields) do
    local at = pos[i]
    if f.opt and lens[i] == 0 then
      -- An optional field not on the wire.
    elseif f.rec then
      -- Each record's fields in order, at their offsets in the frame.
      local k = at
      local w, rec = record_layout(m, f, b, pos)
      if not w then w, rec = f.width, f.rec end
      while k + w <= at + lens[i] do
        for _, g in ipairs(rec) do
          local _, v = int_of(g, b, k + g.offset)
          local range = range_violation(g, nil, v)
          if range then soft[#soft + 1] = out_of_range(m, f.name .. "." .. g.name, k + g.offset, v, range) end
        end
        k = k + w
      end
    elseif f.rep and f.wide then
      for _, x in ipairs(read_wide_list(f, b, at, at + lens[i])) do
        if not wide_within(f, x.w) then
          soft[#soft + 1] = fmt("%s.%s at offset %d is %s, outside its range %s..=%s", m.name, f.name,
            x.at, x.w.text, f.wrange[1], f.wrange[2])
          break
        end
      end
    elseif f.rep then
      local step = f.rep.bit and 0 or f.width
      for k, v in ipairs(read_elements(f, b, at, at + lens[i])) do
        local range = range_violation(f, nil, v)
        if range then soft[#soft + 1] = out_of_range(m, f.name, at + (k - 1) * step, v, range) end
      end
    elseif f.pk and f.wide then
      local e, els = read_wide_elements(f, b, at)
      for _, x in ipairs(els) do
        if not wide_within(e, x.w) then
          soft[#soft + 1] = fmt("%s.%s at offset %d is %s, outside its range %s..=%s", m.name, f.name,
            x.at, x.w.text, f.wrange[1], f.wrange[2])
          break
        end
      end
    elseif f.pk then
      if not packed_padding_clear(f, b, at) then return true end
      for k, v in ipairs(read_packed(f, b, at)) do
        local range = range_violation(f, nil, v)
        if range then soft[#soft + 1] = out_of_range(m, f.name, at + floor((k - 1) * f.pk.bits / 8), v, range) end
      end
    elseif f.wide then
      local w = wide_value(f, b, at)
      if not wide_within(f, w) then
        soft[#soft + 1] = fmt("%s.%s at offset %d is %s, outside its range %s..=%s", m.name, f.name,
          at, w.text, f.wrange[1], f.wrange[2])
      end
    elseif not f.ascii then
      if f.bcd and from_bcd(read_uint(b, at, f.width, f.order)) == nil then return true end
      local u, v = int_of(f, b, at)
      if f.constant and u ~= f.constant then return true end
      if f.follows then
        local o = m.fields[f.follows.field]
        local _, ov = int_of(o, b, pos[f.follows.field])
        if v ~= apply(f.follows, ov) then return true end
      end
      if f.equals then
        local o = m.fields[f.equals]
        local _, ov = int_of(o, b, pos[f.equals])
        if v ~= ov then return true end
      end
      if #f.bits == 0 then
        local range = range_violation(f, nil, v)
        if range then soft[#soft + 1] = out_of_range(m, f.name, at, v, range) end
      end
      for _, bf in ipairs(f.bits) do
        local bv = bit_value(u, bf)
        if bf.constant and bv ~= bf.constant then return true end
        local range = range_violation(f, bf, bv)
        if range then soft[#soft + 1] = out_of_range(m, bf.name, at, bv, range) end
      end
    end
  end
  return false
end

-- A value as busspec's JSON prints it (`field_json`): physical values, special values, enum
-- and flag names.
local function value_json(P, f, bf, v)
  if bf then
    if bf.constant == nil and bf.unit then return physical(P.units[bf.unit], v) end
    return numtext(v)
  end
  if f.constant then return numtext(v) end
  if f.special and f.special[v] then return json_name(f.special[v]) end
  if f.enum then
    local name = P.enums[f.enum][v]
    if name then return json_name(name) end
    return numtext(v)
  end
  if f.flags then
    local items, named = {}, {}
    for _, fl in ipairs(P.flags[f.flags]) do
      named[fl.bit] = true
      if has_bit(v, fl.bit) then items[#items + 1] = json_name(fl.name) end
    end
    for bit = 0, 63 do
      if not named[bit] and has_bit(v, bit) then items[#items + 1] = numtext(2 ^ bit) end
    end
    return "[" .. concat(items, ",") .. "]"
  end
  if f.unit then return physical(P.units[f.unit], v) end
  return numtext(v)
end

local function unit_of(P, f, bf)
  local u
  if bf then
    if bf.constant == nil and bf.unit then u = P.units[bf.unit] end
  elseif not (f.constant or f.enum or f.flags) and f.unit then
    u = P.units[f.unit]
  end
  if u and u.symbol ~= "" then return " " .. u.symbol end
  return ""
end

local function hexw(v, bits)
  local digits = math.ceil(bits / 4)
  if digits < 2 then digits = 2 end
  return fmt("0x%0" .. digits .. "X", v)
end

local f_direction = Field.new("frame.packet_flags_direction")
local f_description = Field.new("frame.interface_description")
local f_time = Field.new("frame.time_epoch")

local function field_value(f)
  local fi = f()
  if fi == nil then return nil end
  return fi.value
end

local function abbrev_part(s)
  return (s:gsub("[^%w_]", "_"))
end

-- One protocol's Proto, fields, expert infos and dissector function.
local function setup(P)
  -- Without an extra byte per message the checksum is its algorithm alone.
  P.checksum.fn = P.checksum.fn or P.checksum.plain
  local abbr = "busspec_" .. abbrev_part(P.name)
  local proto = Proto(abbr, "busspec " .. P.name .. ": " .. P.title)
  local ck_field = ProtoField.uint32
  if P.checksum.width == 8 then ck_field = ProtoField.uint8 elseif P.checksum.width == 16 then ck_field = ProtoField.uint16 end
  local F = {
    message = ProtoField.string(abbr .. ".message", "Message"),
    direction = ProtoField.string(abbr .. ".direction", "Direction"),
    address = ProtoField.uint8(abbr .. ".address", "Address", base.DEC_HEX),
    code = ProtoField.string(abbr .. ".code", "Code"),
    start = ProtoField.bytes(abbr .. ".start", "Start"),
    length = ProtoField.uint32(abbr .. ".length", "Length field"),
    payload = ProtoField.bytes(abbr .. ".payload", "Payload"),
    ends = ProtoField.bytes(abbr .. ".end", "End"),
    checksum = ck_field(abbr .. ".checksum", "Checksum", base.HEX),
    checksum_expected = ck_field(abbr .. ".checksum.expected", "Checksum expected", base.HEX),
    checksum_status = ProtoField.uint8(abbr .. ".checksum.status", "Checksum status", base.DEC,
      { [0] = "Bad", [1] = "Good" }),
    document = ProtoField.string(abbr .. ".document", "Document"),
    section = ProtoField.string(abbr .. ".section", "Section"),
    out_of_spec = ProtoField.string(abbr .. ".out_of_spec", "Out of spec"),
    skipped = ProtoField.uint32(abbr .. ".skipped", "Bytes that start no frame"),
    ambiguous = ProtoField.string(abbr .. ".ambiguous", "Ambiguous"),
    response_to = ProtoField.framenum(abbr .. ".response_to", "Response to frame", base.NONE, frametype.REQUEST),
    response_in = ProtoField.framenum(abbr .. ".response_in", "Response in frame", base.NONE, frametype.RESPONSE),
    time = ProtoField.relative_time(abbr .. ".time", "Time since request"),
  }
  local list = {
    F.message, F.direction, F.address, F.code, F.start, F.length, F.payload, F.ends, F.checksum,
    F.checksum_expected, F.checksum_status, F.document, F.section, F.out_of_spec, F.skipped,
    F.ambiguous, F.response_to, F.response_in, F.time,
  }
  -- Each named value of each message: its value as busspec prints it, and its raw value.
  for _, m in ipairs(P.messages) do
    m.pf = {}
    local leaves = {}
    for _, f in ipairs(m.fields) do
      if #f.bits == 0 then leaves[#leaves + 1] = f.name end
      for _, bf in ipairs(f.bits) do leaves[#leaves + 1] = bf.name end
    end
    for _, leaf in ipairs(leaves) do
      local key = abbr .. ".field." .. abbrev_part(m.name) .. "." .. abbrev_part(leaf)
      local pf = {
        value = ProtoField.string(key, leaf),
        raw = ProtoField.string(key .. ".raw", leaf .. " (raw)"),
      }
      m.pf[leaf] = pf
      list[#list + 1] = pf.value
      list[#list + 1] = pf.raw
    end
  end
  proto.fields = list
  local E = {
    checksum = ProtoExpert.new(abbr .. ".checksum.bad", "Bad checksum", expert.group.CHECKSUM, expert.severity.ERROR),
    out_of_spec = ProtoExpert.new(abbr .. ".out_of_spec.warning", "Out of spec", expert.group.PROTOCOL, expert.severity.WARN),
    skipped = ProtoExpert.new(abbr .. ".skipped.note", "Bytes that start no frame", expert.group.UNDECODED, expert.severity.NOTE),
    ambiguous = ProtoExpert.new(abbr .. ".ambiguous.note", "Ambiguous frame", expert.group.PROTOCOL, expert.severity.NOTE),
  }
  proto.experts = { E.checksum, E.out_of_spec, E.skipped, E.ambiguous }

  -- Constant whole frames (`frame:`, M-Bus's E5) apart: a packet that is one's bytes is it.
  local by_dir = { request = {}, response = {} }
  local constants = { request = {}, response = {} }
  P.commands, P.longest = {}, 0
  for _, m in ipairs(P.messages) do
    local l = by_dir[m.dir]
    if m.frame then l = constants[m.dir] end
    l[#l + 1] = m
    if m.dir == "request" then P.commands[m.idx + 1] = m end
    if m.max_len > P.longest then P.longest = m.max_len end
  end
  -- The order busspec tries them in: messages the frame's code names before code-less ones.
  for _, l in pairs(by_dir) do
    table.sort(l, function(x, y)
      local cx, cy = (#x.code == 0) and 1 or 0, (#y.code == 0) and 1 or 0
      if cx ~= cy then return cx < cy end
      return x.idx < y.idx
    end)
  end

  local state
  local function reset()
    state = { last = nil, frames = {}, response_in = {} }
  end
  reset()
  proto.init = reset

  local function show_leaves(m, b, n, tvb, node)
    local pend = n - trailer_of(P, m)
    local pos, lens = places(m, b, n, pend)
    local info = {}
    for i, f in ipairs(m.fields) do
      local at = pos[i]
      if f.opt and lens[i] == 0 then
        -- An optional field not on the wire: not shown, as busspec's JSON leaves its key out.
      elseif f.rec then
        -- A list of objects, as busspec's JSON prints records; raw, a list of lists.
        local stop = at + lens[i]
        local vals, raws = {}, {}
        local k = at
        local w, rec = record_layout(m, f, b, pos)
        if not w then w, rec = f.width, f.rec end
        while k + w <= stop do
          local kv, kr = {}, {}
          for _, g in ipairs(rec) do
            local _, v = int_of(g, b, k + g.offset)
            kv[#kv + 1] = json_name(g.name) .. ":" .. value_json(P, g, nil, v)
            kr[#kr + 1] = numtext(v)
          end
          vals[#vals + 1] = "{" .. concat(kv, ",") .. "}"
          raws[#raws + 1] = "[" .. concat(kr, ",") .. "]"
          k = k + w
        end
        local value = "[" .. concat(vals, ",") .. "]"
        local range = tvb:range(0, n)
        if stop > at then range = tvb:range(at, stop - at) end
        local item = node:add(m.pf[f.name].value, range, value)
        item:set_text(fmt("%s: %s (%d records)", f.name, value, #vals))
        item:add(m.pf[f.name].raw, range, "[" .. concat(raws, ",") .. "]")
        info[#info + 1] = f.name .. "=" .. value
      elseif (f.rep or f.pk) and not f.ascii then
        local stop, els
        if f.pk then
          stop = at + f.width
          els = read_packed(f, b, at)
        elseif f.wide then
          stop = at + lens[i]
          els = read_wide_list(f, b, at, stop)
        else
          stop = at + lens[i]
          els = read_elements(f, b, at, stop)
        end
        local vals, raws = {}, {}
        if f.wide and f.rep then
          -- Floats and 64-bit integers counted by a field: each printed as busspec prints one.
          for k, x in ipairs(els) do
            vals[k] = x.w.json
            raws[k] = x.w.raw
          end
        elseif f.wide then
          -- Floats and 64-bit integers of a fixed count: each printed as busspec prints one.
          local _, ws = read_wide_elements(f, b, at)
          for k, x in ipairs(ws) do
            vals[k] = x.w.json
            raws[k] = x.w.raw
          end
        else
          for k, v in ipairs(els) do
            vals[k] = value_json(P, f, nil, v)
            raws[k] = numtext(v)
          end
        end
        local value = "[" .. concat(vals, ",") .. "]"
        local range = tvb:range(0, n)
        if stop > at then range = tvb:range(at, stop - at) end
        local item = node:add(m.pf[f.name].value, range, value)
        item:set_text(fmt("%s: %s%s (%d elements; raw [%s])", f.name, value, unit_of(P, f, nil), #els, concat(raws, ",")))
        item:add(m.pf[f.name].raw, range, "[" .. concat(raws, ",") .. "]")
        info[#info + 1] = f.name .. "=" .. value
      elseif f.wide then
        local range = tvb:range(at, f.width)
        local w = wide_value(f, b, at)
        local item = node:add(m.pf[f.name].value, range, w.json)
        item:set_text(f.name .. ": " .. w.json .. unit_of(P, f, nil) .. " (raw " .. w.raw .. ")")
        item:add(m.pf[f.name].raw, range, w.raw)
        info[#info + 1] = f.name .. "=" .. w.json
      elseif f.ascii then
        -- Fixed text takes its width; counted text (`repeat`) as many bytes as its count says;
        -- text up to a terminator its characters (the terminator after them is no character).
        local w = f.width
        if f.rep then w = lens[i] end
        if f.rep and f.rep.count == "until" and w > 0 then w = w - 1 end
        local chars = {}
        for i = 0, w - 1 do chars[#chars + 1] = string.char(b[at + i]) end
        local text = json_bytes(concat(chars))
        local range = tvb:range(0, n)
        local raw = ""
        if w > 0 then
          range = tvb:range(at, w)
          raw = tostring(range:bytes())
        end
        local item = node:add(m.pf[f.name].value, range, text)
        item:set_text(f.name .. ": " .. text)
        item:add(m.pf[f.name].raw, range, raw)
        info[#info + 1] = f.name .. "=" .. text
      else
        local u, v = int_of(f, b, at)
        local range = tvb:range(at, f.width)
        local leaves = f.bits
        if #leaves == 0 then leaves = { false } end
        for _, bf in ipairs(leaves) do
          local name, raw = f.name, v
          if bf then name, raw = bf.name, bit_value(u, bf) end
          local value = value_json(P, f, bf or nil, raw)
          local item = node:add(m.pf[name].value, range, value)
          local bits = ""
          if bf then bits = fmt(", bits %d..%d", bf.lsb, bf.msb) end
          item:set_text(fmt("%s: %s%s (raw %s%s)", name, value, unit_of(P, f, bf or nil), numtext(raw), bits))
          item:add(m.pf[name].raw, range, numtext(raw))
          info[#info + 1] = name .. "=" .. value
        end
      end
    end
    return info
  end

  local dissect_frame

  -- A per-byte transform of the payload (`framing.transform`): the checksum is checked over
  -- the bytes as they travelled, and the fields dissected from a tvb of the frame with the
  -- payload transformed back ("Payload transformed back"). A constant whole frame is its
  -- bytes as they travel.
  -- Payload truncation (`framing.truncation`: MAVLink v2): a frame whose start bytes and
  -- length field agree, whose code names a message and whose payload is 1 byte up to one
  -- less than the message's is dissected with its payload padded with zeros ("Payload padded
  -- with zeros", its length field the padded frame's), as busspec decodes it; its checksum
  -- as it travelled. nil where the frame is dissected as it came.
  local function dissect_truncated(tvb, pinfo, tree)
    local t, n = P.truncation, tvb:len()
    if not t or n < t.payload_at + P.trailer or n > P.longest then return nil end
    local w = {}
    local wa = tvb:range(0, n):bytes()
    for i = 0, n - 1 do w[i] = wa:get_index(i) end
    if t.start_at then
      local function agree(sync)
        for i, x in ipairs(sync) do
          if w[t.start_at + i - 1] ~= x then return false end
        end
        return true
      end
      if not agree(P.sync) and not agree(P.response_sync) then return nil end
    end
    if read_uint(w, t.length_at, t.width, P.order) ~= n + t.k then return nil end
    local full
    for _, c in ipairs(t.codes) do
      local same = true
      for k, x in ipairs(c[1]) do
        if w[t.code_at + k - 1] ~= x then same = false break end
      end
      if same then full = c[2] break end
    end
    if not full then return nil end
    local got = n - t.payload_at - P.trailer
    if got == 0 or got >= full then return nil end
    local wire_ck
    local ck = P.checksum
    local at = checksum_at(P, n)
    if ck.len > 0 then
      wire_ck = { at = at, expected = ck.fn(w, ck.covers_from, at), found = read_uint(w, at, ck.len, ck.order), tvb = tvb }
    end
    local m = t.payload_at + full + P.trailer
    local out = {}
    for i = 0, m - 1 do out[i] = 0 end
    for i = 0, t.payload_at + got - 1 do out[i] = w[i] end
    for i = 0, P.trailer - 1 do out[m - P.trailer + i] = w[at + i] end
    write_uint(out, t.length_at, t.width, P.order, m + t.k)
    local ba = ByteArray.new()
    ba:set_size(m)
    for i = 0, m - 1 do ba:set_index(i, out[i]) end
    dissect_frame(ba:tvb("Payload padded with zeros"), pinfo, tree, wire_ck)
    return n
  end

  local function dissect_transformed(tvb, pinfo, tree)
    if P.truncation then
      local done = dissect_truncated(tvb, pinfo, tree)
      if done then return done end
    end
    local t, n = P.transform, tvb:len()
    if not t or n < t.at + P.trailer or n > P.longest then return dissect_frame(tvb, pinfo, tree) end
    local w = {}
    local wa = tvb:range(0, n):bytes()
    for i = 0, n - 1 do w[i] = wa:get_index(i) end
    for _, d in ipairs({ "request", "response" }) do
      for _, m in ipairs(constants[d]) do
        local same = (#m.frame == n)
        for i, x in ipairs(m.frame) do
          if w[i - 1] ~= x then same = false end
        end
        if same then return dissect_frame(tvb, pinfo, tree) end
      end
    end
    local wire_ck
    local ck = P.checksum
    if ck.len > 0 then
      local at = checksum_at(P, n)
      wire_ck = { at = at, expected = ck.fn(w, ck.covers_from, at), found = read_uint(w, at, ck.len, ck.order), tvb = tvb }
    end
    local ba = ByteArray.new()
    ba:set_size(n)
    for i = 0, n - 1 do
      local x = w[i]
      if i >= t.at and i < n - P.trailer then x = t.undo[x + 1] end
      ba:set_index(i, x)
    end
    return dissect_frame(ba:tvb("Payload transformed back"), pinfo, tree, wire_ck)
  end

  -- A length field whose width the start byte chooses (`framing.length.long`: VESC): the
  -- frame dissected laid out in the long form's width ("Frame laid out in the long form"),
  -- as busspec decodes it: a short frame with the long field's high bytes (zeros), a long one
  -- with the short form's start byte. A long frame whose length the short form holds is
  -- shown as busspec refuses it.
  local function dissect_long(tvb, pinfo, tree)
    local l, n = P.long, tvb:len()
    if not l or n <= l.start_at then return dissect_transformed(tvb, pinfo, tree) end
    local w = {}
    local wa = tvb:range(0, n):bytes()
    for i = 0, n - 1 do w[i] = wa:get_index(i) end
    local b = w[l.start_at]
    local out, m = {}, 0
    if b == l.start then
      if n >= l.length_at + l.width then
        local v = read_uint(w, l.length_at, l.width, l.le and "little" or "big")
        local most = 2 ^ (8 * l.short_width) - 1
        if v <= most then
          pinfo.cols.protocol = P.name
          local text = fmt("long length field at offset %d says %d: lengths up to %d take the short form", l.length_at, v, most)
          local root = tree:add(proto, tvb:range(0, n))
          root:set_text(fmt("busspec %s: %s", P.name, text))
          root:add_proto_expert_info(E.skipped, text)
          pinfo.cols.info = text
          return n
        end
      end
      for i = 0, n - 1 do out[i] = w[i] end
      out[l.start_at] = l.short_start
      m = n
    elseif b == l.short_start and n >= l.length_at + l.short_width then
      local extra = l.width - l.short_width
      local at = l.le and (l.length_at + l.short_width) or l.length_at
      for i = 0, at - 1 do out[i] = w[i] end
      for i = 0, extra - 1 do out[at + i] = 0 end
      for i = at, n - 1 do out[i + extra] = w[i] end
      m = n + extra
    else
      return dissect_transformed(tvb, pinfo, tree)
    end
    -- The checksum as it travelled: the same bytes, from one byte earlier in a short frame.
    local wire_ck
    local ck = P.checksum
    if ck.len > 0 and n >= P.trailer then
      local at = checksum_at(P, n)
      local from = ck.covers_from - (m - n)
      wire_ck = { at = at, expected = ck.fn(w, from, at), found = read_uint(w, at, ck.len, ck.order), tvb = tvb }
    end
    local ba = ByteArray.new()
    ba:set_size(m)
    for i = 0, m - 1 do ba:set_index(i, out[i]) end
    dissect_frame(ba:tvb("Frame laid out in the long form"), pinfo, tree, wire_ck)
    return n
  end

  -- A short form of the frame (`framing.forms`: M-Bus's `10 C A CS 16` beside `68 L L 68
  -- ...`): a short frame dissected laid out in the layout's own form ("Frame laid out in the
  -- long form"), as busspec decodes it: its own start byte replaced, the dropped parts' bytes
  -- of an empty payload put back. A short frame of another length, and a long frame whose
  -- length field says an empty payload, are shown as busspec refuses them.
  local function dissect_form(tvb, pinfo, tree)
    local f, n = P.form, tvb:len()
    if not f or n <= f.start_at then return dissect_transformed(tvb, pinfo, tree) end
    local w = {}
    local wa = tvb:range(0, n):bytes()
    for i = 0, n - 1 do w[i] = wa:get_index(i) end
    local function refuse(text)
      pinfo.cols.protocol = P.name
      local root = tree:add(proto, tvb:range(0, n))
      root:set_text(fmt("busspec %s: %s", P.name, text))
      root:add_proto_expert_info(E.skipped, text)
      pinfo.cols.info = text
      return n
    end
    local b = w[f.start_at]
    if b == f.long_start then
      if n >= f.length_at + f.width then
        local v = read_uint(w, f.length_at, f.width, f.le and "little" or "big")
        if v == f.most then
          return refuse(fmt("long length field at offset %d says %d: lengths up to %d take the short form", f.length_at, v, f.most))
        end
      end
      return dissect_transformed(tvb, pinfo, tree)
    elseif b ~= f.start then
      return dissect_transformed(tvb, pinfo, tree)
    end
    local extra = #f.fill
    local short = f.laid_len - extra
    if n < short then
      return refuse(fmt("truncated frame: need at least %d bytes, found %d", short, n))
    elseif n > short then
      return refuse(fmt("frame too long: %d bytes, the longest frame has %d", n, short))
    end
    local out = {}
    for i = 0, f.at - 1 do out[i] = w[i] end
    for i, x in ipairs(f.fill) do out[f.at + i - 1] = x end
    for i = f.at, n - 1 do out[i + extra] = w[i] end
    out[f.start_at] = f.long_start
    -- The checksum as it travelled: the same bytes, from `extra` bytes earlier.
    local wire_ck
    local ck = P.checksum
    if ck.len > 0 and n >= P.trailer then
      local at = checksum_at(P, n)
      wire_ck = { at = at, expected = ck.fn(w, ck.covers_from - extra, at), found = read_uint(w, at, ck.len, ck.order), tvb = tvb }
    end
    local ba = ByteArray.new()
    ba:set_size(f.laid_len)
    for i = 0, f.laid_len - 1 do ba:set_index(i, out[i]) end
    dissect_frame(ba:tvb("Frame laid out in the long form"), pinfo, tree, wire_ck)
    return n
  end

  -- Escaped frames (`framing.escaping`) are unescaped into a tvb of their own ("Unescaped
  -- frame") and dissected from it; a bad escape is shown as busspec refuses it.
  local function dissect(tvb, pinfo, tree)
    local n = tvb:len()
    -- A flag two frames share (`Framing::shared_flag`, KISS's C0) is in the later frame's
    -- packet alone: a packet that opens with the flag and does not end with it is a frame
    -- whose closing flag is the next packet's first byte, dissected with it put back.
    local flag = P.shared_flag
    if flag and n > 1 and tvb:range(0, 1):uint() == flag and tvb:range(n - 1, 1):uint() ~= flag then
      local ba = tvb:range(0, n):bytes()
      ba:set_size(n + 1)
      ba:set_index(n, flag)
      tvb = ba:tvb("Frame with its shared closing flag")
      n = n + 1
    end
    -- Wake-up bytes before the frame (`framing.preamble`, 0 to its most): shown apart, the
    -- frame dissected from the byte after them, as busspec decodes it.
    local pre = P.preamble
    if pre and n > 0 then
      local k = 0
      while k < pre.max and k < n and tvb:range(k, 1):uint() == pre.byte do k = k + 1 end
      if k > 0 and k < n then
        local item = tree:add(proto, tvb:range(0, k))
        item:set_text(fmt("busspec %s: preamble, %d wake-up byte(s) 0x%02X", P.name, k, pre.byte))
        dissect_transformed(tvb:range(k, n - k):tvb(), pinfo, tree)
        return n
      end
    end
    if P.long then return dissect_long(tvb, pinfo, tree) end
    if P.form then return dissect_form(tvb, pinfo, tree) end
    if not P.escaping or n == 0 then return dissect_transformed(tvb, pinfo, tree) end
    local w = {}
    local wa = tvb:range(0, n):bytes()
    for i = 0, n - 1 do w[i] = wa:get_index(i) end
    -- Responses escaped apart (`response_escaping`: from their first byte, no start byte):
    -- a packet is a response's by its direction, or without one where it does not open
    -- with the requests' start byte.
    local esc
    if P.response_escaping then
      local flags = field_value(f_direction) or 0
      if flags == 1 or (flags ~= 2 and w[0] ~= P.sync[1]) then esc = P.response_escaping end
    end
    local out, k, added, wire_ck = unescape(P, w, n, esc)
    if not out then
      pinfo.cols.protocol = P.name
      local text = fmt("bad escape at offset %d: %s", k, added)
      local root = tree:add(proto, tvb:range(0, n))
      root:set_text(fmt("busspec %s: %s", P.name, text))
      root:add_proto_expert_info(E.skipped, text)
      pinfo.cols.info = text
      return n
    end
    if added == 0 or k == 0 then return dissect_frame(tvb, pinfo, tree) end
    local ba = ByteArray.new()
    ba:set_size(k)
    for i = 0, k - 1 do ba:set_index(i, out[i]) end
    if wire_ck then wire_ck.tvb = tvb end
    dissect_frame(ba:tvb("Unescaped frame"), pinfo, tree, wire_ck)
    return n
  end

  function dissect_frame(tvb, pinfo, tree, wire_ck)
    local n = tvb:len()
    pinfo.cols.protocol = P.name
    local num = pinfo.number
    local rec = state.frames[num]
    local first = false
    if not rec then
      rec = { prev = state.last }
      state.frames[num] = rec
      first = true
    end
    -- The frame's time: exact where the frame's fields are built (a pass with a tree), else
    -- from the double Wireshark gives Lua.
    local t = field_value(f_time)
    if t then
      rec.time = t
    elseif not rec.time then
      local secs = floor(pinfo.abs_ts)
      local ns = floor((pinfo.abs_ts - secs) * 1e9 + 0.5)
      if ns >= 1e9 then secs, ns = secs + 1, ns - 1e9 end
      rec.time = NSTime.new(secs, ns)
    end
    if n == 0 then
      tree:add(proto):set_text("busspec " .. P.name .. ": empty packet")
      return 0
    end
    local whole = tvb:range(0, n)
    local root = tree:add(proto, whole)
    local flags = field_value(f_direction) or 0
    local dirs
    if flags == 2 then dirs = { "request" } elseif flags == 1 then dirs = { "response" } else dirs = { "request", "response" } end

    local strict, lenient = {}, {}
    local b = {}
    local constant
    if n <= P.longest then
      local ba = whole:bytes()
      for i = 0, n - 1 do b[i] = ba:get_index(i) end
      for _, d in ipairs(dirs) do
        for _, m in ipairs(constants[d]) do
          local same = (#m.frame == n)
          for i, x in ipairs(m.frame) do
            if b[i - 1] ~= x then same = false end
          end
          if same then constant = m end
        end
      end
      if constant then
        strict[1] = { m = constant, soft = {} }
        lenient[1] = strict[1]
      end
      for _, d in ipairs(constant and {} or dirs) do
        for _, m in ipairs(by_dir[d]) do
          if structural(P, m, b, n) then
            local soft = {}
            if not misfit(P, m, b, n, soft) then
              local c = { m = m, soft = soft }
              lenient[#lenient + 1] = c
              if #soft == 0 then strict[#strict + 1] = c end
            end
          end
        end
      end
    end
    if #lenient == 0 then
      root:set_text(fmt("busspec %s: %d bytes that start no frame", P.name, n))
      root:add(F.skipped, whole, n)
      root:add_proto_expert_info(E.skipped, fmt("%d bytes that start no frame", n))
      pinfo.cols.info = fmt("%d bytes that start no frame", n)
      return n
    end
    local pool = strict
    local out_of_spec = (#strict == 0)
    if out_of_spec then pool = lenient end

    -- The checksum: over the bytes it covers, up to itself.
    local ck = P.checksum
    local ck_good, ck_at, ck_found, ck_expected = true, nil, nil, nil
    local chosen_name = ""
    local ck_tvb = tvb
    if wire_ck then
      -- Computed on the escaped bytes (`computed: escaped`): as they carry it.
      ck_at, ck_expected, ck_found, ck_tvb = wire_ck.at, wire_ck.expected, wire_ck.found, wire_ck.tvb
      ck_good = (ck_expected == ck_found)
    elseif ck.len > 0 and not constant and not pool[1].m.unchecked then
      -- (A message without a checksum, `checksum: none`, is told apart from every message
      -- with one by its code and length: it has none to check.)
      ck_at = checksum_at(P, n, pool[1].m.dir)
      ck_found = read_uint(b, ck_at, ck.len, ck.order)
      -- Each direction's checksum covers from its own byte (`covers_from: {request,
      -- response}`): the messages whose direction's checksum holds are kept, where any.
      local function ck_from(dir)
        if dir == "response" and ck.response_covers_from then return ck.response_covers_from end
        return ck.covers_from
      end
      -- Up to itself, or to the end bytes where it comes before the bytes it covers.
      local ck_to = ck_at
      if ck.lead then ck_to = n - #ends_of(P, pool[1].m.dir) end
      -- Bytes on both sides of it (HerkuleX's, from the size byte before it): those before
      -- it, then those after it, skipping its own.
      local function ck_sum(from)
        if ck.lead and from < ck.lead then
          local t, k = {}, 0
          for i = from, ck.lead - 1 do t[k] = b[i] k = k + 1 end
          for i = ck.lead + ck.len, ck_to - 1 do t[k] = b[i] k = k + 1 end
          return ck.fn(t, 0, k)
        end
        return ck.fn(b, from, ck_to)
      end
      if ck.response_covers_from then
        local kept = {}
        for _, c in ipairs(pool) do
          if ck_sum(ck_from(c.m.dir)) == ck_found then kept[#kept + 1] = c end
        end
        if #kept > 0 then pool = kept end
      end
      ck_expected = ck_sum(ck_from(pool[1].m.dir))
      ck_good = (ck_expected == ck_found)
    end

    -- A reply whose checksum takes in its request's bytes (`checksum_over_request`): over
    -- those of the request before it, then its own from `over`; not checked without one.
    local ck_unchecked = false
    local function over_request(m)
      if not (m.over and ck_at) or wire_ck then return end
      local cov = rec.prev and rec.prev.cov
      if not cov then
        ck_unchecked, ck_good = true, true
        return
      end
      local t, k = {}, 0
      for _, x in ipairs(cov) do t[k] = x k = k + 1 end
      for i = m.over, ck_at - 1 do t[k] = b[i] k = k + 1 end
      ck_expected = ck.fn(t, 0, k)
      ck_good = (ck_expected == ck_found)
    end

    local function show_checksum()
      if not ck_at then return end
      if ck_unchecked then
        local c = root:add(F.checksum, ck_tvb:range(ck_at, ck.len), ck_found)
        c:append_text(" [" .. ck.name .. ", not checked]")
        c:add_proto_expert_info(E.checksum, fmt("%s's checksum at offset %d takes in its request's bytes: decode it as the reply to its request",
          chosen_name, ck_at))
        return
      end
      local r = ck_tvb:range(ck_at, ck.len)
      local c = root:add(F.checksum, r, ck_found)
      c:append_text(" [" .. ck.name .. "]")
      c:add(F.checksum_expected, r, ck_expected):set_generated()
      c:add(F.checksum_status, r, ck_good and 1 or 0):set_generated()
      if not ck_good then
        c:add_proto_expert_info(E.checksum, fmt("checksum mismatch at offset %d: expected %s, found %s",
          ck_at, hexw(ck_expected, ck.width), hexw(ck_found, ck.width)))
      end
    end

    -- Several messages fit: a request and a response are ambiguous; responses only the
    -- request before this frame tells apart are settled by it (as busspec's stream pairs).
    local chosen
    local has = { request = false, response = false }
    for _, c in ipairs(pool) do has[c.m.dir] = true end
    local prev = rec.prev
    if #pool == 1 then
      chosen = pool[1]
    elseif not (has.request and has.response) and prev then
      local answering = {}
      for _, c in ipairs(pool) do
        if c.m.dir == "response" and P.commands[prev.idx + 1].gets[c.m.idx] then
          answering[#answering + 1] = c
        end
      end
      -- Its values that follow from the request's must (busspec's pairing checks them; a
      -- reply that breaks them is decoded as if unpaired, which its code and length alone
      -- leave ambiguous).
      if #answering == 1 and follows_request(P, answering[1].m, b, n, prev.vals) then
        chosen = answering[1]
      end
    end

    if not chosen then
      local names = {}
      for _, c in ipairs(pool) do names[#names + 1] = c.m.name end
      local text = concat(names, " or ")
      root:set_text(fmt("busspec %s: ambiguous frame: %s", P.name, text))
      root:add(F.ambiguous, whole, text)
      root:add_proto_expert_info(E.ambiguous, "ambiguous frame: could be " .. text .. "; decode it together with the request it answers")
      -- Replies of one code and length whose checksum takes in their request's bytes take
      -- them in at one offset (validated): checked over them as any one of them.
      if pool[1].m.over then
        chosen_name = pool[1].m.name
        over_request(pool[1].m)
      end
      show_checksum()
      if first and ck_good then state.last = nil end
      pinfo.cols.info = "ambiguous: " .. text
      return n
    end

    local m = chosen.m
    chosen_name = m.name
    over_request(m)
    local address = m.address_at and b[m.address_at] or nil
    if first and ck_good then
      if out_of_spec then
        state.last = nil
      elseif m.dir == "request" then
        -- The bytes its checksum covers, for a reply whose checksum takes them in.
        local cov = {}
        if ck.len > 0 then
          -- To the checksum, or to the frame's end where the request has none.
          for i = ck.covers_from, (ck_at or n) - 1 do cov[#cov + 1] = b[i] end
        end
        state.last = { num = num, idx = m.idx, cov = cov, vals = request_values(P, m, b, n) }
      else
        -- A response sent unasked that the request before it does not get is not its reply,
        -- and leaves the request waiting for it.
        local aside = prev and m.unasked and not P.commands[prev.idx + 1].gets[m.idx]
        if prev and not aside then
          rec.response_to = prev
          state.response_in[prev.num] = num
        end
        if not aside then state.last = nil end
      end
    end

    local head = fmt("busspec %s: %s %s", P.name, m.dir, m.name)
    if address then head = head .. fmt(", address %d", address) end
    if not ck_good then head = head .. " [bad checksum]" end
    if ck_unchecked then head = head .. " [checksum not checked]" end
    if out_of_spec then head = head .. " [out of spec]" end
    root:set_text(head)
    local item = root:add(F.message, whole, m.name)
    if m.title ~= "" then item:append_text(" (" .. m.title .. ")") end
    root:add(F.direction, whole, m.dir):set_generated()
    root:add(F.document, whole, P.document):set_generated()
    root:add(F.section, whole, m.section):set_generated()
    if rec.response_to then
      root:add(F.response_to, whole, rec.response_to.num):set_generated()
      local req = state.frames[rec.response_to.num]
      if rec.time and req and req.time then
        root:add(F.time, whole, rec.time - req.time):set_generated()
      end
    end
    if m.dir == "request" and state.response_in[num] then
      root:add(F.response_in, whole, state.response_in[num]):set_generated()
    end
    if m.start_at and #P.sync > 0 then root:add(F.start, tvb:range(m.start_at, #P.sync)) end
    if address then root:add(F.address, tvb:range(m.address_at, 1), address) end
    local rule = P.rules[m.dir]
    if rule and not constant then root:add(F.length, tvb:range(rule.at, rule.width), read_uint(b, rule.at, rule.width, P.order)) end
    root:add(F.code, (#m.code > 0) and tvb:range(m.code_at, #m.code) or whole, m.code_hex)
    local pend = n - trailer_by(P, m.dir)
    local plen = pend - m.payload_at
    local fields_node = root
    if constant then
      item:append_text(" [constant frame]")
    elseif plen > 0 then fields_node = root:add(F.payload, tvb:range(m.payload_at, plen)) end
    local info = show_leaves(m, b, n, tvb, fields_node)
    local ends = ends_of(P, m.dir)
    if #ends > 0 and not constant then root:add(F.ends, tvb:range(end_at(P, n, m.dir), #ends)) end
    show_checksum()
    for _, why in ipairs(chosen.soft) do
      root:add(F.out_of_spec, whole, why):set_generated()
      root:add_proto_expert_info(E.out_of_spec, why)
    end
    local cols = m.dir .. " " .. m.name
    if address then cols = cols .. fmt(" @%d", address) end
    if #info > 0 then cols = cols .. " " .. concat(info, " ") end
    if not ck_good then cols = cols .. " [bad checksum]" end
    if ck_unchecked then cols = cols .. " [checksum not checked]" end
    if out_of_spec then cols = cols .. " [out of spec]" end
    pinfo.cols.info = cols
    return n
  end

  -- The checksum as the spec declares it, checked against the spec's check value.
  if P.checksum.len > 0 then
    local check = {}
    local input = "123456789"
    for i = 1, #input do check[i - 1] = input:byte(i) end
    local got = P.checksum.plain(check, 0, #input)
    if got ~= P.checksum.check then
      error(fmt("busspec %s: the checksum gives 0x%X over \"123456789\", the spec says 0x%X", P.name, got, P.checksum.check))
    end
  end
  return proto, dissect
end

local by_name, only = {}, nil
for _, P in ipairs(SPECS) do
  for i, u in ipairs(P.units) do
    u.A, u.B, u.M = bn_parse(u.A), bn_parse(u.B), bn_parse(u.M)
  end
  local proto, dissect = setup(P)
  by_name[P.name] = { proto = proto, dissect = dissect }
  only = by_name[P.name]
end

local encap = DissectorTable.get("wtap_encap")
if #SPECS == 1 then
  only.proto.dissector = only.dissect
  encap:add(wtap.USER0, only.proto)
else
  local names = {}
  for _, P in ipairs(SPECS) do names[#names + 1] = P.name end
  local dispatch = Proto("busspec", "busspec: " .. concat(names, ", "))
  function dispatch.dissector(tvb, pinfo, tree)
    local d = field_value(f_description)
    local name = d and tostring(d):match("^busspec (.+)$")
    local s = name and by_name[name]
    if not s then
      tree:add(dispatch, tvb:range(0, tvb:len())):set_text(fmt("busspec: the interface (%q) names none of %s", tostring(d), concat(names, ", ")))
      return tvb:len()
    end
    return s.dissect(tvb, pinfo, tree)
  end
  encap:add(wtap.USER0, dispatch)
end
