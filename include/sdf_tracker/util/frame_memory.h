#pragma once

namespace sdf_tracker {

/// Lets a program that processes a stream of frames reuse the memory of one frame for the next.
///
/// Every frame allocates and frees buffers of about a megabyte each: the decoded and the prepared
/// depth image, the tracker's back-projected points, the fusion's block lists. With glibc's
/// defaults such buffers come from fresh mappings or from a heap top that is trimmed as soon as
/// they are freed, so each frame faults its pages in again and zero-fills them. On redkitchen the
/// offline runner spent 6-8 s of its 30-35 s in the kernel that way; with this it takes 19-22 s.
///
/// This keeps buffers below 32 MiB on the heap and trims the heap only when more than 128 MiB lie
/// free at its top. It changes the allocator for the whole process, so it belongs at the top of
/// main() of a program that owns its process (the node, the offline runner), not in a library or
/// a nodelet. Returns false where the C library offers no such setting (the program then runs as
/// before, only slower).
bool keepFrameMemoryResident();

}  // namespace sdf_tracker
