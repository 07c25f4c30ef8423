fn main() {
    println!("dbuffer");
}
