//! `chisel budget`: the bit budget of the exact kernel.

use chisel_bsp::exact::budget::{
    CLASSIFY_BITS, COORD_BITS, MAX_COORD, NORMAL_BITS, OFFSET_BITS, W_BITS, XYZ_BITS,
};

/// (name, magnitude bits, storage) rows of the budget.
fn rows() -> [(&'static str, u32, &'static str); 6] {
    [
        ("input coordinate", COORD_BITS, "i64"),
        ("plane normal a, b, c", NORMAL_BITS, "i64"),
        ("plane offset d", OFFSET_BITS, "i128"),
        ("vertex W", W_BITS, "192-bit"),
        ("vertex X, Y, Z", XYZ_BITS, "256-bit"),
        ("classify dot product", CLASSIFY_BITS, "256-bit"),
    ]
}

/// Prints the budget as a table, or as one JSON line.
pub fn print(json: bool) {
    if json {
        let fields: Vec<String> = rows()
            .iter()
            .map(|(name, bits, storage)| {
                format!("{{\"quantity\":\"{name}\",\"magnitude_bits\":{bits},\"storage\":\"{storage}\"}}")
            })
            .collect();
        println!(
            "{{\"max_coord\":{MAX_COORD},\"budget\":[{}]}}",
            fields.join(",")
        );
        return;
    }
    println!("input coordinates: |v| <= {MAX_COORD} (2^{COORD_BITS}); at 1 mm per unit, +-67 km");
    println!("{:<24} {:>6}  storage", "quantity", "bits");
    for (name, bits, storage) in rows() {
        println!("{name:<24} {bits:>6}  {storage}");
    }
}
