//! Every random spec the generator draws is one the validator accepts: a refusal is a bug of
//! the generator (`difftest` counts it as one), found here without compiling anything.

use busspec_difftest::gen::random_spec;

fn refusals(seeds: impl IntoIterator<Item = u64>) -> Vec<String> {
    seeds
        .into_iter()
        .filter_map(|s| {
            let text = random_spec(s);
            busspec_model::load_str(&format!("s{s}.yaml"), &text)
                .err()
                .map(|d| format!("seed {s}: {d}"))
        })
        .collect()
}

#[test]
fn a_record_of_one_byte_field_stays_a_record_beside_counted_text() {
    // Seeds 291 and 296 drew a record list whose one field is a `u8`; the counted-text draw
    // took it for a plain byte list and cut the record's YAML apart.
    assert_eq!(refusals([291, 296]), Vec::<String>::new());
}

#[test]
fn the_first_five_hundred_seeds_give_valid_specs() {
    assert_eq!(refusals(1..=500), Vec::<String>::new());
}

/// The generator draws responses sent unasked (`unasked: true`): replies also sent unasked and
/// responses no command lists, so the differential meets them after requests.
#[test]
fn some_seeds_draw_responses_sent_unasked() {
    let (mut also, mut only) = (0, 0);
    for s in 1..=300 {
        let Ok(p) = busspec_model::load_str(&format!("s{s}.yaml"), &random_spec(s)) else {
            continue;
        };
        also += usize::from(
            p.responses
                .iter()
                .any(|m| m.unasked && !m.answers.is_empty()),
        );
        only += usize::from(
            p.responses
                .iter()
                .any(|m| m.unasked && m.answers.is_empty()),
        );
    }
    assert!(also >= 5 && only >= 10, "also {also}, only {only}");
}

/// The generator draws FrSky's end-around sum (`sum8_end_around`), masked and not, so the
/// differential holds the generated `rt::sum8_end_around` to the interpreter's.
#[test]
fn some_seeds_draw_the_end_around_sum() {
    use busspec_model::ir::ChecksumAlgorithm as A;
    let (mut plain, mut masked) = (0, 0);
    for s in 1..=300 {
        let Ok(p) = busspec_model::load_str(&format!("s{s}.yaml"), &random_spec(s)) else {
            continue;
        };
        match &p.framing.checksum.algorithm {
            A::Sum8EndAround => plain += 1,
            A::Masked(a, _) if **a == A::Sum8EndAround => masked += 1,
            _ => {}
        }
    }
    assert!(plain >= 15 && masked >= 1, "plain {plain}, masked {masked}");
}
