pub mod expert;
