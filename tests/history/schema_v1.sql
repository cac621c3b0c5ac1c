-- A history as shadowbench wrote it at schema version 1 (summary rows only, no
-- per-frame figures), with one night in it: the history test opens it with
-- today's shadowbench, which must migrate it to the current version and keep
-- the night.
CREATE TABLE nights(id INTEGER PRIMARY KEY, set_key TEXT UNIQUE NOT NULL, dir TEXT, date TEXT, host TEXT,
 renderer TEXT, version TEXT, git_commit TEXT, header TEXT, meta TEXT, added TEXT);
CREATE TABLE runs(id INTEGER PRIMARY KEY, night INTEGER NOT NULL REFERENCES nights(id), run_id TEXT,
 run_index INTEGER, series TEXT, scene TEXT, path TEXT, technique TEXT, params TEXT, size TEXT, status TEXT,
 reason TEXT, stable TEXT, warnings TEXT, line TEXT);
CREATE TABLE metrics(run INTEGER NOT NULL, name TEXT NOT NULL, value REAL, PRIMARY KEY(run, name)) WITHOUT ROWID;
CREATE INDEX runs_night ON runs(night);
CREATE INDEX runs_series ON runs(series);
INSERT INTO nights(set_key, dir, date, host, renderer, version, git_commit, header, meta, added)
 VALUES ('v1-night', '/old', '2026-01-01T00:00:00Z', 'old-host', 'llvmpipe', '0.1.0', 'abc', 'run_id', '', '2026-01-01T00:00:00Z');
PRAGMA user_version = 1;
