"""The station's internal referee: a game-controller stand-in for classes and tests."""
