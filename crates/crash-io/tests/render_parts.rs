//! Pieces of the pictures: tick choice, number and time labels, the font's coverage.

use crash_io::render::font::glyph;
use crash_io::render::plot::nice_ticks;
use crash_io::render::scene::{format_number, format_time};

#[test]
fn ticks_are_round_numbers_inside_the_range() {
    assert_eq!(
        nice_ticks(0.0, 1.0, 5),
        vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
    );
    let t = nice_ticks(-0.3, 6.1, 6);
    assert_eq!(
        t,
        vec![0.0, 2.0, 4.0, 6.0],
        "step 2: the first of 1, 2, 5 x 10^k above 6.4 / 6"
    );
    // 0.0767 / 6 = 0.0128 -> step 0.02.
    let t = nice_ticks(0.0, 0.0767, 6);
    assert_eq!(t.len(), 4, "{t:?}");
    assert!((t[3] - 0.06).abs() < 1e-15);
    assert_eq!(nice_ticks(2.0, 2.0, 5), vec![2.0]);
}

#[test]
fn labels_are_short_and_readable() {
    assert_eq!(format_number(0.0), "0");
    assert_eq!(format_number(60.6125), "60.6");
    assert_eq!(format_number(0.25), "0.25");
    assert_eq!(format_number(1234.0), "1234");
    assert_eq!(format_number(2.5e-5), "2.5e-5");
    assert_eq!(format_number(3.0e7), "3e7");
    assert_eq!(format_time(0.0), "0 s");
    assert_eq!(format_time(7.607e-5), "76.070 us");
    assert_eq!(format_time(1.25e-3), "1.250 ms");
    assert_eq!(format_time(2.0), "2.0000 s");
}

#[test]
fn font_has_every_character_the_pictures_use() {
    let used = "0123456789.-+e t=usmstep[MPa]von Mises energy [J] time [ms] kinetic internal \
                hourglass contact damping external work total - Energy balance";
    let missing = glyph('\u{1F600}');
    for c in used.chars() {
        assert!(c == ' ' || glyph(c) != missing, "glyph for {c:?}");
    }
    // Descenders hang below the 7-row line; other letters do not.
    assert_eq!(glyph('g').len(), 9);
    assert_eq!(glyph('a').len(), 7);
}
