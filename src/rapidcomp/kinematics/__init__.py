"""Robot kinematics: model, thermal profile, confdata, inverse kinematics."""
