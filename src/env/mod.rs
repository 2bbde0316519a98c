pub mod obstacle;
