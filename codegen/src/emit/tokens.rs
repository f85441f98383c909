use super::*;

/// `snake_case` to `CamelCase`, as generated type names are spelled.
pub fn camel(snake: &str) -> String {
    let mut out = String::with_capacity(snake.len());
    for part in snake.split('_') {
        let mut c = part.chars();
        if let Some(f) = c.next() {
            out.push(f.to_ascii_uppercase());
            out.push_str(c.as_str());
        }
    }
    out
}

pub(super) fn ident(s: &str) -> Ident {
    Ident::new(s, Span::call_site())
}

/// The generated local variable holding a field's value.
pub(super) fn local(name: &str) -> Ident {
    format_ident!("v_{}", name)
}

/// The local a field's wire value is bound to (`w_quantity`), where a later field, a list's
/// count or an optional field's condition reads it: named after the field, as `local` names
/// its typed value.
pub(super) fn wire_local(name: &str) -> Ident {
    format_ident!("w_{}", name)
}

pub(super) fn type_ident(snake: &str) -> Ident {
    let c = camel(snake);
    // A name starting with a digit after an underscore split cannot happen: names start with a letter.
    ident(&c)
}

pub(super) fn doc(text: &str) -> TokenStream {
    let lines: Vec<TokenStream> = text
        .lines()
        .map(|l| {
            let l = doc_lit(&format!(" {}", escape_brackets(l.trim_end())));
            quote!(#[doc = #l])
        })
        .collect();
    quote!(#(#lines)*)
}

/// A doc attribute's text as a raw string literal where prettyplease prints the attribute as a
/// `///` or `//!` line (one line, not starting with `/`), escaped otherwise: the line printed
/// is the same, and syn reads a raw string back without unescaping it a character at a time.
pub(super) fn doc_lit(text: &str) -> Literal {
    if text.contains(['\n', '\r']) || text.starts_with('/') {
        return Literal::string(text);
    }
    let mut fence = String::new();
    while text.contains('"') && text.contains(&format!("\"{fence}")) {
        fence.push('#');
    }
    format!("r{fence}\"{text}\"{fence}")
        .parse()
        .unwrap_or_else(|_| Literal::string(text))
}

/// Escapes the brackets of document text (`0.02 [A]`, `[pF]`), which rustdoc would read as
/// links; the generator's own links, written ``[`Name`]``, stay links.
pub(super) fn escape_brackets(line: &str) -> String {
    if !line.contains(['[', ']']) {
        return line.to_owned();
    }
    let mut out = String::with_capacity(line.len() + 8);
    let (mut prev, mut chars) = (None, line.chars().peekable());
    while let Some(c) = chars.next() {
        let link_open = c == '[' && chars.peek() == Some(&'`');
        let link_close = c == ']' && prev == Some('`');
        if (c == '[' || c == ']') && !link_open && !link_close {
            out.push('\\');
        }
        out.push(c);
        prev = Some(c);
    }
    out
}

pub(super) fn inner_doc(text: &str) -> TokenStream {
    let lines: Vec<TokenStream> = text
        .lines()
        .map(|l| {
            let l = doc_lit(&format!(" {}", l.trim_end()));
            quote!(#![doc = #l])
        })
        .collect();
    quote!(#(#lines)*)
}

pub(super) fn lit_u(v: u64, t: IntType) -> TokenStream {
    let s = format!("0x{v:X}{}", t.ident());
    s.parse().unwrap_or_else(|_| quote!(0))
}

pub(super) fn direction_names(d: Direction) -> (Ident, &'static str) {
    match d {
        Direction::Request => (ident("Request"), "A request (command), host to device."),
        Direction::Response => (ident("Response"), "A response, device to host."),
    }
}

pub(super) fn variant(m: &Message) -> Ident {
    type_ident(&m.name)
}

/// A byte as the documents print it: `0x2A`.
pub(super) fn hex_u8(b: u8) -> TokenStream {
    format!("0x{b:02X}").parse().unwrap_or_else(|_| quote!(#b))
}

/// Bytes as the documents print a frame: `E5`, `10 5B`.
pub(super) fn hex_spaced(bytes: &[u8]) -> String {
    let hex: Vec<String> = bytes.iter().map(|b| format!("{b:02X}")).collect();
    hex.join(" ")
}

/// A code as the documents print it, one or more bytes as one hex number: `0x4072`.
pub(super) fn hex_code(code: &[u8]) -> TokenStream {
    let digits: String = code.iter().map(|b| format!("{b:02X}")).collect();
    let v = code_value(code);
    format!("0x{digits}").parse().unwrap_or_else(|_| quote!(#v))
}

pub(super) fn code_value(code: &[u8]) -> u32 {
    code.iter().fold(0u32, |a, b| (a << 8) | u32::from(*b))
}

/// An unsuffixed hex literal.
pub(super) fn hex_lit(v: u64) -> TokenStream {
    format!("{v:#X}")
        .replace("0X", "0x")
        .parse()
        .unwrap_or_else(|_| quote!(#v))
}

pub(super) fn usize_lit(v: usize) -> Literal {
    Literal::usize_unsuffixed(v)
}

pub(super) fn i64_lit(v: i64) -> Literal {
    Literal::i64_unsuffixed(v)
}

/// The wire bytes of constant `c` in a field of `width` bytes.
pub(super) fn constant_bytes(c: u64, width: usize, order: ByteOrder) -> Vec<u8> {
    let le: Vec<u8> = (0..width).map(|i| (c >> (8 * i)) as u8).collect();
    match order {
        ByteOrder::Little => le,
        ByteOrder::Big => le.into_iter().rev().collect(),
    }
}

pub(super) fn to_bytes(order: ByteOrder) -> Ident {
    match order {
        ByteOrder::Little => format_ident!("to_le_bytes"),
        ByteOrder::Big => format_ident!("to_be_bytes"),
    }
}

/// Whether `tokens` name the local `frame`.
pub(super) fn mentions_frame(tokens: &TokenStream) -> bool {
    tokens.clone().into_iter().any(|t| match t {
        proc_macro2::TokenTree::Ident(i) => i == "frame",
        proc_macro2::TokenTree::Group(g) => mentions_frame(&g.stream()),
        _ => false,
    })
}

/// `e` in parentheses if it has a binary operator or a cast at its top level, so it can take a
/// cast or a method call.
pub(super) fn paren(e: TokenStream) -> TokenStream {
    let bare = e.clone().into_iter().all(|t| match t {
        proc_macro2::TokenTree::Punct(p) => !"<>&|+-*/%^".contains(p.as_char()),
        proc_macro2::TokenTree::Ident(i) => i != "as",
        _ => true,
    });
    if bare {
        e
    } else {
        quote!((#e))
    }
}

/// A type as the `request`/`response` modules name it: every path that starts at a type of the
/// generated module (`Angle`, `rt::Repeated<Angle, 4>`) or at `rt` starts at `super::` instead,
/// so a message's struct, which lives in that module, can be named as a spec type is
/// (`codegen/tests/fixtures/core_names.yaml` names a message as a type).
pub(super) fn in_parent(t: TokenStream) -> TokenStream {
    use proc_macro2::{Group, TokenTree};
    let mut out = TokenStream::new();
    let mut after_colons = false;
    for tt in t {
        match tt {
            TokenTree::Ident(i) => {
                let s = i.to_string();
                if !after_colons && (s == "rt" || s.starts_with(|c: char| c.is_ascii_uppercase())) {
                    out.extend(quote!(super::));
                }
                out.extend([TokenTree::Ident(i)]);
                after_colons = false;
            }
            TokenTree::Group(g) => {
                let mut ng = Group::new(g.delimiter(), in_parent(g.stream()));
                ng.set_span(g.span());
                out.extend([TokenTree::Group(ng)]);
                after_colons = false;
            }
            TokenTree::Punct(p) => {
                after_colons = p.as_char() == ':';
                out.extend([TokenTree::Punct(p)]);
            }
            other => {
                after_colons = false;
                out.extend([other]);
            }
        }
    }
    out
}
