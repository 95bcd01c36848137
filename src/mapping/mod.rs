//! Grid mapping (DESIGN §2 "Mapping"): shared observation model, occupancy grid, EKF, map
//! metrics and map files. (Being written: issue "Grid mapping I".)
