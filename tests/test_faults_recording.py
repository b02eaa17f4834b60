"""Faults of the recorder without a node: a full disk (a file object that refuses bytes while
the disk is full, as ENOSPC does), a bag folder deleted while recording, an unwritable folder,
and ``recover`` on a file that is not MCAP. Every failure is one ``RecordingError`` line and
the file is finished as far as it got."""

from __future__ import annotations

import errno
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
import yaml

from biped_gait.recording.background import BackgroundRecorder
from biped_gait.recording.qos import qos_description
from biped_gait.recording.recorder_process import RecorderProcess
from biped_gait.recording.reader import open_bag
from biped_gait.recording.recover import is_complete, recover
from biped_gait.recording.writer import RESERVE_NAME, McapRecorder, RecordingError

from .test_recording import JOINTS, STRING, joint_state, string

pytestmark = [pytest.mark.faults, pytest.mark.recording]

STREAM = qos_description("keep_last", 50, "reliable", "volatile")
LATCHED = qos_description("keep_last", 1, "reliable", "transient_local")
ENTRY = shutil.which("biped-gait", path=str(Path(sys.executable).parent))


class FullDisk:
    """An opener whose files take ``room`` bytes, then refuse with ENOSPC (after a partial
    write, as the kernel does) while the disk is full: until the recorder frees its reserve
    (``frees_space``), or for ever."""

    def __init__(self, room: int, frees_space: bool = True) -> None:
        self.room, self.frees_space, self.refused = room, frees_space, 0

    def __call__(self, path: Path):
        disk, raw = self, open(path, "xb", buffering=0)
        reserve = path.parent / RESERVE_NAME

        class File:
            def write(self, data) -> int:
                full = disk.room <= 0 and not (disk.frees_space and not reserve.exists())
                if full:
                    disk.refused += 1
                    raise OSError(errno.ENOSPC, "No space left on device")
                count = raw.write(bytes(data[:max(disk.room, 1)] if disk.room > 0 else data))
                disk.room -= count
                return count

            def fileno(self) -> int:
                return raw.fileno()

            def close(self) -> None:
                raw.close()

        return File()


def record_until_it_fails(recorder: McapRecorder, limit: int = 5000) -> tuple[int, RecordingError | None]:
    recorder.add_topic("/robot_description", STRING, [LATCHED])
    recorder.add_topic("/joint_states", JOINTS, [STREAM])
    recorder.write("/robot_description", string("<robot/>"), 1)
    for i in range(limit):
        try:
            recorder.write("/joint_states", joint_state(i), 10 + i)
        except RecordingError as exc:
            return i + 1, exc
    return limit, None


def test_a_full_disk_is_one_line_and_the_file_is_finished(tmp_path):
    disk = FullDisk(room=20_000)
    recorder = McapRecorder(tmp_path, "bag", chunk_size=2048, opener=disk)
    written, error = record_until_it_fails(recorder)
    assert error is not None and disk.refused == 1
    message = str(error)
    assert "\n" not in message and message.startswith("recording failed: ") and "No space left on device" in message
    assert recorder.closed and not (recorder.bag_dir / RESERVE_NAME).exists()
    recorder.write("/joint_states", joint_state(0), 1)  # after the failure: ignored, no second error
    recorder.close()
    assert is_complete(recorder.path)  # finished as far as it got: nothing handed over is lost
    bag = open_bag(recorder.bag_dir)
    assert bag.topics() == {"/robot_description": (STRING, 1), "/joint_states": (JOINTS, written)}
    assert bag.offered_qos("/joint_states") == [STREAM] and bag.offered_qos("/robot_description") == [LATCHED]


def test_a_disk_that_stays_full_leaves_a_recoverable_file(tmp_path):
    recorder = McapRecorder(tmp_path, "bag", chunk_size=2048, opener=FullDisk(room=20_000, frees_space=False))
    _, error = record_until_it_fails(recorder)
    assert error is not None and "'biped-gait recover' rebuilds what it holds" in str(error)
    assert not is_complete(recorder.path)
    out = tmp_path / "recovered" / "recovered_0.mcap"
    out.parent.mkdir()
    assert recover(recorder.path, out) > 0 and is_complete(out)
    info = yaml.safe_load((out.parent / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert all(t["topic_metadata"]["offered_qos_profiles"] for t in info["topics_with_message_count"])


def test_a_deleted_bag_folder_is_one_line(tmp_path):
    recorder = McapRecorder(tmp_path, "bag", chunk_size=1024)
    recorder.add_topic("/joint_states", JOINTS, [STREAM])
    shutil.rmtree(recorder.bag_dir)
    with pytest.raises(RecordingError, match="was deleted while recording"):
        for i in range(1000):
            recorder.write("/joint_states", joint_state(i), i)


def test_a_bag_folder_deleted_before_close_is_one_line(tmp_path):
    recorder = McapRecorder(tmp_path, "bag")
    recorder.add_topic("/joint_states", JOINTS, [STREAM])
    recorder.write("/joint_states", joint_state(0), 1)
    shutil.rmtree(recorder.bag_dir)
    with pytest.raises(RecordingError, match="was deleted while recording"):
        recorder.close()


def test_an_unwritable_folder_is_one_line(tmp_path):
    (tmp_path / "a_file").write_text("")
    with pytest.raises(RecordingError, match=r"^recording failed: cannot create .*a_file/bags/bag: Not a directory$"):
        McapRecorder(tmp_path / "a_file" / "bags", "bag")


def test_recover_refuses_what_is_not_mcap(tmp_path):
    (tmp_path / "notes.mcap").write_bytes(b"\x00\x01binary\xff" * 100)
    done = subprocess.run([ENTRY, "recover", str(tmp_path / "notes.mcap")], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and done.stderr == f"biped-gait: error: {tmp_path / 'notes.mcap'}: not an MCAP file\n"
    assert not (tmp_path.parent / "notes_recovered").exists()


def test_the_background_recorder_reports_a_full_disk_once_and_finishes_the_file(tmp_path):
    """The writer thread meets the full disk; the next write says so (one line), later ones and
    ``close`` are quiet, and the file holds what was handed over before the failure."""
    recorder = BackgroundRecorder(McapRecorder(tmp_path, "bag", chunk_size=2048, opener=FullDisk(room=20_000)))
    recorder.add_topic("/joint_states", JOINTS, [STREAM])
    errors = []
    for i in range(20_000):
        try:
            recorder.write("/joint_states", joint_state(i), 10 + i)
        except RecordingError as exc:
            errors.append(str(exc))
        if i % 500 == 499:
            time.sleep(0.05)  # the writer thread's turn
    recorder.close()
    assert len(errors) == 1 and "No space left on device" in errors[0] and "\n" not in errors[0]
    assert is_complete(recorder.path) and recorder.failure == errors[0]
    [(_, (datatype, count))] = open_bag(recorder.bag_dir).topics().items()
    assert datatype == JOINTS and 0 < count < 20_000


def test_an_owners_on_failure_hears_of_a_full_disk_once_whichever_thread_writes(tmp_path):
    """A node writes from its walk, its timers and its services: with ``on_failure`` the failure
    goes to the owner once (not to whichever thread happened to write next), and no write or
    ``close`` raises."""
    heard = []
    recorder = BackgroundRecorder(McapRecorder(tmp_path, "bag", chunk_size=2048, opener=FullDisk(room=20_000)),
                                  on_failure=lambda error: heard.append(str(error)))
    recorder.add_topic("/joint_states", JOINTS, [STREAM])

    def writer(first: int) -> None:
        for i in range(first, 20_000, 2):
            recorder.write("/joint_states", joint_state(i), 10 + i)
            if i % 1000 < 2:
                time.sleep(0.05)  # the writer thread's turn

    threads = [threading.Thread(target=writer, args=(k,)) for k in (0, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    recorder.close()
    assert len(heard) == 1 and "No space left on device" in heard[0] and recorder.failure == heard[0]
    assert is_complete(recorder.path)


def test_the_background_recorder_serializes_off_the_callers_path_and_drains_at_close(tmp_path):
    recorder = BackgroundRecorder(McapRecorder(tmp_path, "bag"))
    recorder.add_topic("/robot_description", STRING, [LATCHED])
    recorder.write("/robot_description", lambda: string("<robot/>"), 1)  # serialized on the writer thread
    for i in range(3000):
        recorder.write("/robot_description", string(str(i)), 2 + i)
    recorder.close()
    assert open_bag(recorder.bag_dir).topics() == {"/robot_description": (STRING, 3001)}
    info = yaml.safe_load((recorder.bag_dir / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    [entry] = info["topics_with_message_count"]
    assert entry["topic_metadata"]["type_description_hash"].startswith("RIHS01_")


def test_the_recorder_process_says_what_the_recorder_says(tmp_path):
    """A recorder in a process of its own: the same one-line failures, raised in the caller,
    and a file that readers open once closed."""
    (tmp_path / "a_file").write_text("")
    with pytest.raises(RecordingError, match=r"^recording failed: cannot create .*a_file/bags/bag: Not a directory$"):
        RecorderProcess(tmp_path / "a_file" / "bags", "bag")
    recorder = BackgroundRecorder(RecorderProcess(tmp_path, "bag", chunk_size=1024))
    with pytest.raises(FileExistsError):
        RecorderProcess(tmp_path, "bag")
    recorder.add_topic("/joint_states", JOINTS, [STREAM])
    for i in range(500):
        recorder.write("/joint_states", joint_state(i), i)
    recorder.close()
    assert open_bag(recorder.bag_dir).topics() == {"/joint_states": (JOINTS, 500)}
    deleted = BackgroundRecorder(RecorderProcess(tmp_path, "deleted", chunk_size=1024))
    deleted.add_topic("/joint_states", JOINTS, [STREAM])
    shutil.rmtree(deleted.bag_dir)
    errors = []
    for i in range(3000):
        try:
            deleted.write("/joint_states", joint_state(i), i)
        except RecordingError as exc:
            errors.append(str(exc))
        if i % 500 == 499:
            time.sleep(0.05)
    deleted.close()
    assert len(errors) == 1 and "was deleted while recording" in errors[0]
