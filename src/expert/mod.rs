pub mod lqr;

pub mod ppo;

pub mod vo;

pub mod vo_policy;
