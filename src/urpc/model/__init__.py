"""The robot and what is known about it: URDF loading (Pinocchio), the robot catalog, the
uncertainty box over link parameters, the Slotine-Li regressor, and modular-arm assembly."""
