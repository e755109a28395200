"""Motion control: pure controllers that turn a target and a robot state into a local velocity."""
