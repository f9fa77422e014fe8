"""``python -m beadrod.models.laws.greenwood_williamson --rebuild``: the law's table."""

from beadrod.models.laws.greenwood_williamson import TABLE_PATH, build_table
from beadrod.models.tables.rebuild import rebuild_cli

raise SystemExit(rebuild_cli(None, prog="python -m beadrod.models.laws.greenwood_williamson",
                             description="Tabulated Greenwood-Tripp rough-sphere load-approach "
                             "law.", build=build_table, path=TABLE_PATH))
