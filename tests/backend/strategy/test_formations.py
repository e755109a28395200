from backend.strategy.formations import FormationConfig, formation


def test_formations_stay_on_our_half_and_inside_the_field() -> None:
    cfg = FormationConfig()
    for k in range(3):
        for n in (1, 6, 11):
            pts = formation(k, n, cfg)
            assert len(pts) == n
            for x, y in pts:
                assert -4500 < x < 0 and abs(y) < 3000
