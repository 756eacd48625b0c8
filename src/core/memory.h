#pragma once
// Process-wide allocator set-up shared by the entry points (CLI, benches).
namespace u3d {

// Makes glibc's malloc keep freed memory in the process: blocks under 256 MiB come from the heap,
// which is never trimmed. Both ISOMER (megabyte buffers every optimisation step) and the networks
// (tensors of tens of megabytes every layer) otherwise have their freed blocks unmapped and fault the
// same pages in again on the next step. Blocks of 256 MiB and more (the VAE's activations at 1024 px
// and above: 0.5-1 GiB each, in a few sizes) get their own mapping, returned when freed: in the heap
// they leave holes that the next, larger block cannot use: a 1024 px decode in fp32 peaked at 9.75 GiB
// that way and peaks at 5.5 GiB now (bench_vae --op=decode --size=1024; 4.65 GiB with 64 MiB, but
// then the UNets' tensors of 64-128 MiB are mapped and faulted in anew every step). The heap never
// shrinks by itself: see release_freed_memory().
void keep_freed_memory_for_reuse();

// Returns the heap's free pages to the system (malloc_trim), wherever they lie in it. Called where a
// large amount of memory has just been freed and will not be reused as it is: after a checkpoint's
// tensors are copied into a network, and after a network stage frees its networks. Without it that
// memory stays resident, and the next network's allocations, of other sizes, grow the heap beside it.
void release_freed_memory();

// The memory the process can still take, in MiB: the kernel's MemAvailable, or less where the process's
// cgroup (v2: a Slurm or Kubernetes memory limit) has a limit with less left under it. 0 when neither
// can be read.
double available_memory_mib();

}  // namespace u3d
