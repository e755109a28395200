"""Strategy: who goes where. The end-to-end loop ships a formation demo."""
