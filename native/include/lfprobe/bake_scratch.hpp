// Scratch arrays of a probe's bake, kept for the next probe of the same set.
//
// A bake allocates its scratch arrays by the hundred megabytes: a 2048² probe from the lab room's
// four 0.1° scans takes about 1.4 GB (its cut's 16 M points and splat shapes, its texels'
// directions, fronts and colour sums). Fresh from the kernel, every page of them is faulted in
// and zeroed before the bake writes it: a tenth of that bake. While a BakeScratchScope lives
// on a thread, the bakes run on that thread take their arrays from it and hand them back when
// done, so a set's next probe writes into pages that are already there.
#pragma once

#include <cstddef>
#include <memory>
#include <type_traits>

namespace lfprobe {

class BakeScratchPool;

// Everything the scope keeps is freed when it ends. Scopes nest: the innermost serves.
class BakeScratchScope {
public:
    BakeScratchScope();
    ~BakeScratchScope();
    BakeScratchScope(const BakeScratchScope&) = delete;
    BakeScratchScope& operator=(const BakeScratchScope&) = delete;

    // The pool of the innermost scope on this thread; null outside every scope.
    [[nodiscard]] static std::shared_ptr<BakeScratchPool> current();

private:
    std::shared_ptr<BakeScratchPool> pool_;
    BakeScratchScope* outer_;
};

// `bytes` bytes, unset (their contents are whatever a previous bake left), aligned for any
// scalar type: the smallest block the thread's scope holds that is large enough, else new.
// Handed back to that scope when destroyed, or freed where the scope has ended.
class ScratchBytes {
public:
    explicit ScratchBytes(std::size_t bytes);
    ~ScratchBytes();
    ScratchBytes(ScratchBytes&&) noexcept = default;
    ScratchBytes(const ScratchBytes&) = delete;
    ScratchBytes& operator=(const ScratchBytes&) = delete;
    ScratchBytes& operator=(ScratchBytes&&) = delete;

    [[nodiscard]] std::byte* data() const { return block_.get(); }

private:
    std::unique_ptr<std::byte[]> block_;
    std::size_t size_ = 0; // the block's size, at least the bytes asked for
    std::weak_ptr<BakeScratchPool> pool_;
};

// `count` elements of a type with no constructor or destructor to run, left unset as
// std::make_unique_for_overwrite leaves them: a bake writes every element before reading it.
template <class T>
class ScratchArray {
    static_assert(std::is_trivially_default_constructible_v<T> &&
                      std::is_trivially_destructible_v<T>,
                  "scratch arrays hold plain data");

public:
    explicit ScratchArray(std::size_t count) : bytes_(count * sizeof(T)) {}

    [[nodiscard]] T* get() const { return reinterpret_cast<T*>(bytes_.data()); }
    T& operator[](std::size_t i) const { return get()[i]; }
    // False for an array of no elements (what a bake that keeps none asks for).
    explicit operator bool() const { return bytes_.data() != nullptr; }

private:
    ScratchBytes bytes_;
};

} // namespace lfprobe
