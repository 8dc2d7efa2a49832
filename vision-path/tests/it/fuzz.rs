//! Hostile items (NaN, infinities, huge and tiny numbers, zero vectors, negative times,
//! discontinuities): the stream never panics, never yields a non-finite setpoint, and an error
//! is always the last thing it yields.

use proptest::prelude::*;
use vision_path::Xyz;
use vision_path::{
    ArcShape, Event, Item, Limits, OutputCommand, PathMode, PlanConfig, Rate, Segment, Setpoints, Shape,
    SpindleCommand, Step,
};

fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -50.0..50.0f64,
        1 => prop::sample::select(vec![0.0, -0.0, 1e-300, -1e-12, 1e9, 1e300, -1e300, f64::MAX, f64::MIN_POSITIVE, f64::NAN, f64::INFINITY, f64::NEG_INFINITY]),
    ]
}

fn xyz() -> impl Strategy<Value = Xyz> {
    prop::array::uniform3(number()).prop_map(Xyz::from)
}

fn item() -> impl Strategy<Value = Item> {
    let mode = prop_oneof![
        Just(PathMode::ExactStop),
        prop::option::of(number()).prop_map(|tolerance| PathMode::Blend { tolerance })
    ];
    let rate = prop_oneof![Just(Rate::Rapid), number().prop_map(|f| Rate::Feed(f * 100.0))];
    let shape = prop_oneof![
        Just(Shape::Line),
        (xyz(), xyz(), number()).prop_map(|(centre, normal, sweep)| Shape::Arc(ArcShape { centre, normal, sweep })),
    ];
    prop_oneof![
        6 => (1..100usize, xyz(), xyz(), shape, rate, mode)
            .prop_map(|(line, start, end, shape, rate, mode)| Item::Move(Segment { line, start, end, shape, rate, mode })),
        1 => (1..100usize, number()).prop_map(|(line, seconds)| Item::Dwell { line, seconds }),
        1 => (1..100usize).prop_map(|line| Item::Event {
            line,
            event: Event::Output(OutputCommand::Tool { tool: None, command: SpindleCommand::Stop }),
        }),
        1 => (1..100usize).prop_map(|line| Item::End { line }),
    ]
}

/// Makes most moves continuous (each starts where the previous one ended), so the planner
/// gets past the continuity check and meets the other hostile numbers.
fn chain(mut items: Vec<Item>, start: Xyz, keep: &[bool]) -> Vec<Item> {
    let mut pos = start;
    for (item, keep) in items.iter_mut().zip(keep.iter().cycle()) {
        if let Item::Move(seg) = item {
            if !keep {
                seg.start = pos;
            }
            pos = seg.end;
        }
    }
    items
}

/// `PROPTEST_CASES` overrides the default case count (for deeper local runs).
fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(512), ..ProptestConfig::default() })]

    #[test]
    fn hostile_items_give_finite_setpoints_or_a_final_error(
        items in prop::collection::vec(item(), 0..10),
        keep in prop::collection::vec(prop::bool::weighted(0.1), 1..4),
        period in prop::sample::select(vec![1e-5, 0.001, 0.01, 1.0]),
    ) {
        let config = PlanConfig::new(Limits::uniform(1000.0, 500.0, 1000.0), period, Xyz::ZERO);
        let items = chain(items, Xyz::ZERO, &keep);
        let mut stream = Setpoints::from_items(&config, items).unwrap();
        let mut failed = false;
        // Enough steps for the interesting part; a valid program may legitimately run far longer.
        for step in stream.by_ref().take(200_000) {
            prop_assert!(!failed, "nothing follows an error");
            match step {
                Ok(Step::Setpoint(s)) => {
                    prop_assert!(s.time.is_finite());
                    prop_assert!(s.position.is_finite() && s.velocity.is_finite(), "{:?}", s);
                }
                Ok(Step::Event(e)) => prop_assert!(e.time.is_finite()),
                Err(e) => {
                    prop_assert!(e.line().is_some(), "{e}");
                    failed = true;
                }
            }
        }
    }
}
